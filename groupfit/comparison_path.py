"""The grouped models ``compare`` fits on the modelling run, p = 1…pmax, and the path of R against p.

The path is the certified optimum of every p (:func:`groupfit.models.select_p.exact_path`),
and each GA model's gap to it is recorded. A run whose exact path would take
longer than the budget is compared on the GA's own models instead, the path
marked as not certified, rather than refused.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from groupfit.models.grouped import GroupedRegressor
from groupfit.models.select_p import exact_path
from groupfit.objective import grouped_residuals
from groupfit.search.base import SearchSettings


def grouped_path(
    X: np.ndarray,
    y: np.ndarray,
    pmax: int,
    *,
    n: int,
    c: float,
    objective: str,
    fit_intercept: bool,
    search: SearchSettings,
    certified: bool = True,
    progress: Callable[[str, float], None] | None = None,
) -> tuple[dict, dict[int, GroupedRegressor]]:
    """The path of R against p (``certified``: the exact optimum) and the GA's grouped model of every p >= 1.

    Returns
    -------
    path : dict
        ``breaks``, ``objective``, ``rss``, ``R`` (lists indexed by p) and ``certified``.
    grouped : dict
        p -> the fitted :class:`GroupedRegressor` (its ``search_`` holds the gap to the optimum when certified).
    """
    settings = {"n": n, "c": c, "objective": objective, "fit_intercept": fit_intercept}
    path = exact_path(X, y, pmax if certified else 0, **settings)
    if certified:
        pmax = len(path["breaks"]) - 1
    search = search.replace(method="ga", certify=False)
    grouped: dict[int, GroupedRegressor] = {}
    if progress is not None:
        progress("grouped", 0.0)  # the stage's clock starts with its first fit
    for p in range(1, pmax + 1):
        estimator = GroupedRegressor.from_settings(p=p, **settings, search=search)
        grouped[p] = estimator.fit(X, y, progress=None if progress is None else _per_fit(progress, p))
        info = grouped[p].search_
        if certified:
            exact_value = path["objective"][p]
            info.update(exact_objective=exact_value, exact_breaks=path["breaks"][p])
            info["gap_percent"] = 100.0 * (info["search_objective"] - exact_value) / exact_value
        else:
            _, residuals = grouped_residuals(X, y, grouped[p].breaks_, n=n, fit_intercept=fit_intercept)
            path["breaks"].append(list(grouped[p].breaks_))
            path["objective"].append(float(info["search_objective"]))
            path["rss"].append(float(np.sum(residuals**2)))
            path["R"].append(float(np.sum(np.abs(residuals))))
        if progress is not None:
            progress("grouped", p / pmax)
    path["certified"] = certified
    return path, grouped


def _per_fit(progress: Callable[[str, float], None], p: int) -> Callable[[str, float], None]:
    """The search's own progress within the fit of ``p`` breaks, as a stage of its own (``ga p = 2``)."""
    return lambda stage, fraction: progress(f"{stage} p = {p}", fraction)


__all__ = ["grouped_path"]
