"""The diagnosis's figure: the residual against the effect found, and the residual before/after on every run."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from groupfit.diagnose.augment import feature_on_runs, steady_reference
from groupfit.io import save_figure
from groupfit.plots import subplots


def stacked_hours(runs) -> np.ndarray:
    """Hours along several runs laid end to end (each run's own clock from its start)."""
    hours, offset = [], 0.0
    for run in runs:
        hours.append(offset + (run.time - run.time[0]) / 3600.0)
        offset = hours[-1][-1] + run.period / 3600.0
    return np.concatenate(hours)


def plot_diagnosis(result, runs: dict, path: str | Path) -> None:
    """Residual against the winning candidate, and the residual before/after on every run (runs laid end to end)."""
    runs = {key: [value] if not isinstance(value, (list, tuple)) else list(value) for key, value in runs.items()}
    fig, axes = subplots(1 + len(runs), 1, figsize=(9, 3.2 * (1 + len(runs))), constrained_layout=True)
    data = runs["data"]
    shown = result.added[0] if result.added else (result.candidates[0] if result.candidates else None)
    top = axes[0]
    if shown is not None:
        feature = shown.feature
        period = result.model.sampling_period_s  # as the diagnosis computed it
        values = np.concatenate(feature_on_runs(feature, data, period))
        if shown.over is not None:  # taken over the model's reference column, as the diagnosis took it
            steady = steady_reference(shown.over)
            values = values - np.concatenate(feature_on_runs(steady, data, period))
        residual = result.residuals_before["data"]
        top.scatter(values, residual, s=6, c=stacked_hours(data), cmap="viridis")
        order = np.argsort(values)
        finite = np.isfinite(residual)
        fit = np.polyfit(values[finite], residual[finite], 1)
        top.plot(values[order], np.polyval(fit, values[order]), color="tab:red", lw=1.2)
        verdict = "added" if result.added else "best candidate, not significant"
        top.set_title(
            f"{'+'.join(r.name for r in data)}: residual against {feature.column}, {shown.describe()} ({verdict})",
            fontsize=9,
        )
        top.set_xlabel(feature.name if shown.over is None else f"{feature.name} − {steady.name}")
    top.set_ylabel("residual before (µm)")
    for axis, (key, key_runs) in zip(axes[1:], runs.items()):
        hours = stacked_hours(key_runs)
        before, after = result.residuals_before[key], result.residuals_after[key]
        rms = lambda r: float(np.sqrt(np.nanmean(r**2)))  # noqa: E731
        axis.plot(hours, before, color="tab:gray", lw=1.0, label=f"before (RMS {rms(before):.3g} µm)")
        axis.plot(hours, after, color="tab:blue", lw=1.0, label=f"after (RMS {rms(after):.3g} µm)")
        axis.axhline(0.0, color="black", lw=0.5)
        names = "+".join(r.name for r in key_runs)
        axis.set_title(f"{names} ({'measured' if key == 'data' else 'validation'}): residual", fontsize=9)
        axis.set_ylabel("µm")
        axis.legend(fontsize=8)
    axes[-1].set_xlabel("time (h)")
    save_figure(fig, path, dpi=110)
