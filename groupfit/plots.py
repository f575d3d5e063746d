"""Figures (matplotlib, written as PNG files)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from groupfit.io import save_figure


def subplots(*grid, figsize, constrained_layout: bool = True, **options):
    """A figure of its own (no pyplot, no global backend) and its axes."""
    fig = Figure(figsize=figsize, layout="constrained" if constrained_layout else None)
    return fig, fig.subplots(*grid, **options)


def plot_fit(
    time_s: np.ndarray,
    measured: np.ndarray,
    predicted: np.ndarray,
    breaks: Sequence[int],
    soft_groups: Sequence[Sequence[int]],
    path: str | Path,
    title: str = "",
    break_intervals=None,
    label: str = "grouped model",
) -> None:
    """Measured vs predicted error over time, hard and soft breaks marked, residual panel below.

    ``break_intervals`` (BreakInterval objects) are drawn as shaded bands around their breaks.
    """
    hours = np.asarray(time_s, dtype=float) / 3600.0
    residual = np.asarray(measured) - np.asarray(predicted)
    fig, (top, bottom) = subplots(
        2, 1, figsize=(9, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]}, constrained_layout=True
    )
    top.plot(hours, measured, color="black", lw=1.6, label="measured")
    top.plot(hours, predicted, color="tab:red", lw=1.2, ls="--", label=label)
    for k, b in enumerate(breaks):
        for axis in (top, bottom):
            axis.axvline(
                hours[b - 1], color="tab:blue", lw=1.0, label="hard break" if (k == 0 and axis is top) else None
            )
    for k, (first, _) in enumerate(soft_groups[1:]):
        for axis in (top, bottom):
            axis.axvline(
                hours[first - 1],
                color="tab:blue",
                lw=0.8,
                ls=":",
                label="soft break" if (k == 0 and axis is top) else None,
            )
    for k, interval in enumerate(i for i in (break_intervals or []) if i.lower is not None):
        for axis in (top, bottom):
            label = f"{100 * interval.level:g} % break interval ({interval.method})" if k == 0 and axis is top else None
            axis.axvspan(
                hours[interval.lower - 1], hours[interval.upper - 1], color="tab:blue", alpha=0.15, label=label
            )
    top.set_ylabel("thermal error (µm)")
    top.legend(loc="best", fontsize=8)
    top.set_title(title)
    bottom.plot(hours, residual, color="tab:gray", lw=1.0)
    bottom.axhline(0.0, color="black", lw=0.6)
    bottom.set_ylabel("residual (µm)")
    bottom.set_xlabel("time (h)")
    save_figure(fig, path, dpi=120)


def plot_dataset(frame, path: str | Path, title: str = "") -> None:
    """Temperatures (top) and thermal error (bottom) of a data set over time.

    The top panel shows the sensor columns and ``T_amb`` (dashed); candidate
    node columns (``node_*``) and condition columns are left out. A data set
    whose only input is a heat flux (the rod scenario) shows ``q_W_m2`` instead.
    """
    hours = frame["time_s"].to_numpy(dtype=float) / 3600.0
    skip = {"time_s", "error_um", "speed_rpm", "spindle_on", "q_W_m2"}
    temps = [c for c in frame.columns if c not in skip and not c.startswith(("node_", "src_"))]
    fig, (top, bottom) = subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    if temps:
        for column in temps[:12]:
            top.plot(hours, frame[column], label=column, linestyle="--" if column == "T_amb" else "-")
        top.set_ylabel("temperature (°C)")
        top.legend(ncol=4, fontsize="small")
    elif "q_W_m2" in frame:
        top.step(hours, frame["q_W_m2"], where="pre")
        top.set_ylabel("heat flux q (W/m²)")
    top.set_title(title)
    if "error_um" in frame:
        bottom.plot(hours, frame["error_um"], color="k")
    bottom.set_ylabel("thermal error (µm)")
    bottom.set_xlabel("time (h)")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
    save_figure(fig, Path(path), dpi=120)


MODEL_STYLE = {
    "mlr": ("MLR", "tab:green", "-."),
    "fit": ("fit's model", "tab:cyan", "-"),
    "ar1": ("AR(1) free run", "tab:orange", ":"),
}


def plot_run_comparison(
    time_s, measured, predictions: dict, path: str | Path, title: str, grouped_shown=(1, 2, 4), bands=None
) -> None:
    """Measured vs predicted error of the compared models on one run, residuals below.

    ``bands`` maps a model key to its (lower, upper) prediction band, shaded in the model's colour.
    """
    hours = np.asarray(time_s, dtype=float) / 3600.0
    fig, (top, bottom) = subplots(
        2, 1, figsize=(10, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.6]}, constrained_layout=True
    )
    measured = np.asarray(measured, dtype=float)
    points = {"ls": "none", "marker": "."} if not np.isfinite(measured).all() else {}  # a sparse error: its readings
    top.plot(hours, measured, color="black", lw=2.0, label="measured", **points)
    grouped_colors = iter(["tab:blue", "tab:purple", "tab:red", "tab:brown", "tab:pink", "tab:olive"])
    shown = [key for key in predictions if key in MODEL_STYLE] + [
        f"grouped{p}" for p in grouped_shown if f"grouped{p}" in predictions
    ]
    for key in shown:
        if key in MODEL_STYLE:
            label, color, style = MODEL_STYLE[key]
        else:
            label, color, style = f"grouped p = {key[7:]}", next(grouped_colors), "--"
        top.plot(hours, predictions[key], color=color, ls=style, lw=1.3, label=label)
        if bands and bands.get(key) is not None:
            lower, upper = (np.asarray(end) - predictions[key] for end in bands[key])
            top.fill_between(hours, predictions[key] + lower, predictions[key] + upper, color=color, alpha=0.12, lw=0)
            bottom.fill_between(hours, lower, upper, color=color, alpha=0.12, lw=0)
        bottom.plot(hours, measured - predictions[key], color=color, lw=1.0, **({"ls": style} | points))
    bottom.axhline(0.0, color="black", lw=0.6)
    if bands:
        bottom.set_title("shaded: 95 % prediction bands, centred on each model's prediction", fontsize=8)
    top.set_ylabel("thermal error (µm)")
    top.legend(fontsize=8, loc="best")
    top.set_title(title)
    bottom.set_ylabel("residual (µm)")
    bottom.set_xlabel("time (h)")
    save_figure(fig, path, dpi=120)


def plot_r_against_p(
    path_R: Sequence[float], rows: Sequence[dict], runs: Sequence[str], path: str | Path, *, certified: bool = True
) -> None:
    """The paper's R (µm) against p: the certified optimum and each run's grouped models, MLR and AR(1) marked.

    The legend stands right of the axes (never over the data) and p is marked at whole numbers only.
    """
    fig, axis = subplots(figsize=(9.5, 4.5), constrained_layout=True)
    label = "exact optimum" if certified else "GA, not certified (over the exact search's budget)"
    axis.plot(range(len(path_R)), path_R, "k-o", lw=1.6, label=f"{runs[0]}: {label}")
    markers = "sD^v"
    for i, run in enumerate(runs):
        grouped = sorted((r["p"], r["R_um"]) for r in rows if r["run"] == run and r["model"] == "grouped")
        mlr = [r["R_um"] for r in rows if r["run"] == run and r["model"] == "mlr"]
        if grouped:
            ps, values = zip(*([(0, mlr[0])] if mlr else []) + grouped) if mlr else zip(*grouped)
            axis.plot(ps, values, ls="--", marker=markers[i % 4], lw=1.0, label=f"{run}: fitted models")
        ar1 = [r["R_um"] for r in rows if r["run"] == run and r["model"] == "ar1"]
        if ar1:
            axis.axhline(ar1[0], ls=":", lw=1.0, color=f"C{i}", label=f"{run}: AR(1)")
    axis.set_yscale("log")
    axis.set_xlabel("hard break points p")
    axis.set_ylabel("R = Σ|e| (µm)")
    axis.set_xticks(range(len(path_R)))
    axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    save_figure(fig, path, dpi=120)


def heating_phases(error: np.ndarray, window: int) -> np.ndarray:
    """True where the error rises: the sign of its slope over ``window`` samples either side (NaN-free error)."""
    error = np.asarray(error, dtype=float)
    index = np.arange(len(error))
    ahead = error[np.minimum(index + window, len(error) - 1)]
    behind = error[np.maximum(index - window, 0)]
    return ahead >= behind


def plot_hysteresis(
    temps: np.ndarray, names: Sequence[str], error: np.ndarray, path: str | Path, title: str = ""
) -> None:
    """Error against each input (pseudo-hysteresis, Du et al. Fig. 1), rising and falling error drawn apart.

    Where heating and cooling trace different curves no single temperature maps to the
    error: the signature of a sensor that leads or lags the deformation.
    """
    temps, error = np.asarray(temps, dtype=float), np.asarray(error, dtype=float)
    count = temps.shape[1]
    columns = min(count, 3)
    rows = -(-count // columns)
    fig, axes = subplots(rows, columns, figsize=(3.6 * columns, 3.2 * rows), squeeze=False)
    rising = heating_phases(error, max(1, len(error) // 100))
    for j, axis in enumerate(axes.ravel()):
        if j >= count:
            axis.set_visible(False)
            continue
        axis.plot(temps[:, j], error, color="0.8", lw=0.6, zorder=1)
        axis.scatter(temps[rising, j], error[rising], s=4, color="tab:red", label="error rising", zorder=2)
        axis.scatter(temps[~rising, j], error[~rising], s=4, color="tab:blue", label="error falling", zorder=2)
        axis.set_xlabel(names[j])
        axis.set_ylabel("thermal error (µm)")
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(title)
    save_figure(fig, path, dpi=120)
