"""The error metrics and residual checks the diagnosis reports, before and after."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from groupfit.data import Run
from groupfit.diagnose.checks import drift, ljung_box
from groupfit.diagnose.result import Metrics, RunMetrics
from groupfit.metrics import error_metrics


def metrics_of(res: np.ndarray) -> dict[str, float]:
    return error_metrics(res[np.isfinite(res)])


def metrics_per_run(
    runs: Sequence[Run], skipped: Sequence[int], before: np.ndarray, after: np.ndarray
) -> tuple[RunMetrics, ...]:
    """The error metrics of each of ``runs`` before and after, cut from the stacked residuals (a run's history
    rows, ``skipped``, are not in them); runs without a measured error are left out."""
    edges = np.cumsum([0, *(len(run.time) - skip for run, skip in zip(runs, skipped))])
    out = []
    for run, start, end in zip(runs, edges[:-1], edges[1:]):
        if np.isfinite(before[start:end]).any():
            out.append(RunMetrics(run.name, metrics_of(before[start:end]), metrics_of(after[start:end])))
    return tuple(out)


def joint_name(runs: list[Run]) -> str:
    return runs[0].name if len(runs) == 1 else "+".join(r.name for r in runs)


def residual_checks(res: np.ndarray, time_s: np.ndarray) -> dict[str, Metrics]:
    rows = np.isfinite(res)
    return {"ljung_box": ljung_box(res[rows]), "drift": drift(res[rows], time_s[rows])}
