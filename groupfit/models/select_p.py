"""How many breaks: an information criterion, or the paper's target rule.

* ``bic``: the Bayesian information criterion of each fitted model under
  Gaussian residuals, ``N·ln(RSS/N) + k·ln(N)`` with
  ``k = (p+1)·M + p + 1`` (coefficients, break positions, variance), the
  count strucchange uses for segmented regressions; the smallest wins.
* ``target``: the fewest breaks whose residual sum R meets a target, given in
  µm or as a percentage of R at p = 0 (``"20%"``), as the paper chooses p.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from groupfit.errors import InputError
from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost, grouped_residuals
from groupfit.search.exact import solve_exact

RULES = ("bic", "target")


def bic(rss: float, n_samples: int, p: int, n_coef: int) -> float:
    """BIC of a grouped model with p breaks and M = ``n_coef`` coefficients per group."""
    parameters = (p + 1) * n_coef + p + 1
    return n_samples * np.log(max(rss, np.finfo(float).tiny) / n_samples) + parameters * np.log(n_samples)


def parse_target(target: str | float | None, r_at_zero: float) -> float | None:
    """A target in µm from a number or a percentage of R(p = 0)."""
    if target is None:
        return None
    if isinstance(target, str):
        text = target.strip()
        try:
            if text.endswith("%"):
                return float(text[:-1]) / 100.0 * r_at_zero
            return float(text)
        except ValueError:
            raise InputError(
                f"p target {target!r}: give µm (e.g. 5.0) or a percentage of R(p = 0) (e.g. 20%)"
            ) from None
    return float(target)


def choose_p(
    rss: Sequence[float],
    residual_sums: Sequence[float],
    n_samples: int,
    n_coef: int,
    rule: str = "bic",
    target: str | float | None = None,
) -> dict:
    """Choose p from per-p fits (index = p).

    Parameters
    ----------
    rss : sequence of float
        Residual sum of squares of the fitted model for p = 0, 1, ….
    residual_sums : sequence of float
        The paper's R (sum of |e|) for the same fits.
    rule : {"bic", "target"}
    target : str or float, optional
        For the target rule: µm, or a percentage of R(p = 0).

    Returns
    -------
    dict
        ``p`` (the choice, or None when no p meets the target), ``rule``,
        ``bic`` (per p), ``target_um``.
    """
    if rule not in RULES:
        raise InputError(f"p rule {rule!r}: choose one of {', '.join(RULES)}")
    criteria = [bic(v, n_samples, p, n_coef) for p, v in enumerate(rss)]
    target_um = parse_target(target, residual_sums[0]) if residual_sums else None
    if rule == "bic":
        chosen = int(np.argmin(criteria))
    else:
        if target_um is None:
            raise InputError("the target rule needs a target: --p-target 5.0 (µm) or 20% (of R at p = 0)")
        meeting = [p for p, value in enumerate(residual_sums) if value <= target_um]
        chosen = meeting[0] if meeting else None
    return {"rule": rule, "p": chosen, "bic": [float(c) for c in criteria], "target_um": target_um}


def exact_path(X, y, pmax: int, *, n: int, c: float, objective: str, fit_intercept: bool) -> dict:
    """Certified optimum for every p in 0…pmax (one dynamic-programming pass) and its fit.

    Returns
    -------
    dict
        ``breaks``, ``objective``, ``rss``, ``R`` (lists indexed by p, up to
        the largest feasible p), ``seconds``.
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float)
    n_coef = X.shape[1] + int(fit_intercept)
    constraints = Constraints.for_model(len(y), n, c, n_coef)
    constraints.require(0, c, n_coef)
    result = solve_exact(SegmentCost(X, y, n=n, objective=objective, fit_intercept=fit_intercept), constraints, pmax)
    path = {"breaks": [], "objective": [], "rss": [], "R": [], "seconds": result.seconds}
    for p in sorted(result.breaks):
        _, residuals = grouped_residuals(X, y, result.breaks[p], n=n, fit_intercept=fit_intercept)
        path["breaks"].append(result.breaks[p])
        path["objective"].append(result.objective[p])
        path["rss"].append(float(np.sum(residuals**2)))
        path["R"].append(float(np.sum(np.abs(residuals))))
    return path
