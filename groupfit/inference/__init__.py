"""How sure is a grouped model? Break-position and prediction intervals.

* :mod:`.break_intervals` — Bai's (1997) confidence intervals of least-squares
  break estimates (``sse``, n = 0), as strucchange's ``confint`` gives them;
* :mod:`.bootstrap` — a residual block bootstrap of the breaks for the other
  settings (``sae``, soft groups n > 0);
* :mod:`.prediction` — per-group OLS prediction intervals
  (``GroupedRegressor.predict(X, return_interval=True)``).

:func:`break_intervals` chooses between the first two for a fitted model.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from groupfit.errors import InputError
from groupfit.inference.bootstrap import BootstrapTooSlow, bootstrap_break_intervals
from groupfit.inference.break_intervals import BreakInterval, bai_intervals
from groupfit.objective import design_matrix
from groupfit.search.base import DEFAULT_SEED
from groupfit.search.exact import exact_is_cheap

METHODS = ("auto", "bai", "bootstrap", "none")


@dataclass
class BreakIntervalReport:
    """Break intervals of one model and how they were obtained.

    Attributes
    ----------
    intervals : list of BreakInterval
        One per hard break (empty when not computed).
    method : str
        ``"bai"``, ``"bootstrap"`` or ``"none"``.
    detail : str
        How they were obtained (variant, replicates), or why there are none.
    level : float
    seconds : float or None
        Time the bootstrap took, or would have taken when it was skipped.
    """

    intervals: list[BreakInterval] = field(default_factory=list)
    method: str = "none"
    detail: str = ""
    level: float = 0.95
    seconds: float | None = None

    def summary(self, n_samples: int | None = None) -> str:
        """One line for a printed report; with ``n_samples``, the breaks :func:`weak_breaks` flags."""
        if self.seconds is None:
            text = self.detail
        elif not self.intervals:
            text = f"{self.detail} (it would take about {self.seconds:.0f} s)"
        else:
            text = f"{self.detail}, {self.seconds:.1f} s"
        if n_samples is not None:
            weak = weak_breaks(self.intervals, n_samples)
            if weak:
                text += "; weak: " + "; ".join(f"break {b} ({why})" for b, why in weak.items())
        return text

    def to_json(self) -> list[dict]:
        return [interval.to_dict() for interval in self.intervals]

    def text_for(self, brk: int) -> str:
        """``[lower, upper]`` of a break, or ``-``."""
        for interval in self.intervals:
            if interval.brk == brk:
                return interval.text()
        return "-"


def bai_applies(objective: str, n: int) -> bool:
    """Bai's asymptotics are those of least squares with disjoint segments: sse and n = 0."""
    return objective == "sse" and int(n) == 0


def break_intervals(
    estimator,
    X,
    y,
    method: str = "auto",
    level: float = 0.95,
    *,
    het: bool = True,
    n_boot: int = 200,
    block: int | None = None,
    seed: int = DEFAULT_SEED,
    budget_s: float | None = None,
    progress: bool | Callable[[str, float], None] = False,
) -> BreakIntervalReport:
    """Confidence intervals of a fitted grouped model's hard breaks.

    Parameters
    ----------
    estimator : GroupedRegressor
        Fitted on (X, y).
    X, y : array-like
        The modelling run it was fitted on.
    method : {"auto", "bai", "bootstrap", "none"}
        ``auto``: Bai where it applies (:func:`bai_applies`), the bootstrap
        otherwise. ``bai`` with sae or n > 0 is refused.
    level : float
        Confidence level.
    het : bool
        Bai: heteroskedastic regressors and errors across segments
        (strucchange's default) or one common Q and σ².
    n_boot, block, seed, progress
        Bootstrap settings (:func:`groupfit.inference.bootstrap.bootstrap_break_intervals`).
    budget_s : float, optional
        With ``method="auto"``: give up on the bootstrap (``method = "none"``,
        the reason in ``detail``) when the first replicate projects a longer run.

    Returns
    -------
    BreakIntervalReport
        Ends clipped to the feasible break range 1…N−1.
    """
    if method not in METHODS:
        raise InputError(f"interval method {method!r}: choose one of {', '.join(METHODS)}")
    if not 0.0 < level < 1.0:
        raise InputError(f"level = {level:g} must lie strictly between 0 and 1")
    if n_boot < 1:
        raise InputError(f"--bootstrap {n_boot}: the bootstrap needs at least 1 refit")
    if block is not None and block < 1:
        raise InputError(f"--block {block}: bootstrap blocks hold at least 1 sample")
    breaks = list(estimator.breaks_)
    if method == "none" or not breaks:
        return BreakIntervalReport(detail="not computed" if method == "none" else "no breaks", level=level)
    applies = bai_applies(estimator.objective, estimator.n)
    if method == "bai" and not applies:
        raise InputError(
            "Bai's break intervals need --objective sse and --n 0 (least squares, disjoint groups); "
            "use the bootstrap for this model"
        )
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    n_samples = len(y)
    if method == "bai" or (method == "auto" and applies):
        design = design_matrix(X, fit_intercept=estimator.fit_intercept)
        raw = bai_intervals(design, y, breaks, level=level, het_reg=het, het_err=het)
        variant = "heteroskedastic regressors and errors" if het else "common Q and sigma"
        return BreakIntervalReport([_clip(i, n_samples) for i in raw], "bai", f"Bai (1997), {variant}", level)

    fewest = math.ceil(2.0 / (1.0 - level) - 1e-9)  # each tail of the percentile interval holds a refit
    if n_boot < fewest:
        raise InputError(
            f"--bootstrap {n_boot}: a {100 * level:g} % interval needs at least {fewest} refits (each tail, "
            f"{50 * (1 - level):g} %, at least one); give --bootstrap {fewest} or more"
        )
    search_s = float((getattr(estimator, "search_", None) or {}).get("seconds") or 0.0)
    by_ga = not exact_is_cheap(n_samples, estimator.objective)  # the refits search as the fit did
    if method == "auto" and budget_s is not None and by_ga and search_s * n_boot > budget_s:
        return _bootstrap_not_run(n_boot, level, search_s * n_boot)
    started = time.perf_counter()
    try:
        result = bootstrap_break_intervals(
            X,
            y,
            breaks,
            n=estimator.n,
            c=estimator.c,
            objective=estimator.objective,
            fit_intercept=estimator.fit_intercept,
            level=level,
            n_boot=n_boot,
            block=block,
            seed=seed,
            progress=progress,
            budget_s=budget_s if method == "auto" else None,
        )
    except BootstrapTooSlow as slow:
        return _bootstrap_not_run(n_boot, level, slow.projected_s)
    seconds = time.perf_counter() - started
    detail = (
        f"residual block bootstrap, {n_boot} refits ({result.search} search), blocks of {result.block} samples, "
        f"seed {seed}"
    )
    return BreakIntervalReport(result.intervals, "bootstrap", detail, level, seconds)


def _bootstrap_not_run(n_boot: int, level: float, projected_s: float) -> BreakIntervalReport:
    """The report of an automatic bootstrap that would exceed its budget (``projected_s`` seconds)."""
    return BreakIntervalReport(
        detail=f"not computed: ask for the bootstrap ({n_boot} refits) with --intervals bootstrap; "
        "Bai's intervals need the sse objective and n = 0",
        level=level,
        seconds=projected_s,
    )


def weak_breaks(intervals: list[BreakInterval], n_samples: int, share: float = 0.5) -> dict[int, str]:
    """Breaks the rule of thumb of ``docs/intervals.md`` calls not worth keeping, with the reason.

    * When the intervals of two neighbouring breaks overlap, the data cannot
      tell the two apart: the break with the wider interval is flagged.
    * A break whose interval spans more than ``share`` of the shorter of the
      two hard groups it separates is hardly placed by the data.

    Breaks without an interval are not judged.
    """
    edges = [0, *(i.brk for i in intervals), n_samples]
    weak: dict[int, str] = {}

    def width(interval: BreakInterval) -> int:
        return interval.upper - interval.lower + 1

    for left, right in zip(intervals[:-1], intervals[1:]):
        if left.lower is None or right.lower is None or left.upper < right.lower:
            continue
        wider, other = (left, right) if width(left) >= width(right) else (right, left)
        weak.setdefault(wider.brk, f"its interval overlaps that of break {other.brk}, which is narrower")
    for j, interval in enumerate(intervals):
        if interval.lower is None or interval.brk in weak:
            continue
        shorter = min(edges[j + 1] - edges[j], edges[j + 2] - edges[j + 1])
        if width(interval) > share * shorter:
            weak[interval.brk] = f"its interval spans more than {share:.0%} of the shorter group beside it"
    return dict(sorted(weak.items()))


def _clip(interval: BreakInterval, n_samples: int) -> BreakInterval:
    if interval.lower is None:
        return interval
    lower = min(max(1, interval.lower), interval.brk)
    upper = max(min(n_samples - 1, interval.upper), interval.brk)
    return BreakInterval(interval.brk, lower, upper, interval.level, interval.method)


__all__ = ["BreakInterval", "BreakIntervalReport", "bai_intervals", "break_intervals", "bai_applies", "weak_breaks"]
