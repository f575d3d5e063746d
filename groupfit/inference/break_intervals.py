"""Confidence intervals of break positions by Bai (1997), as strucchange computes them.

For a linear regression with m structural breaks estimated by least squares
(the ``sse`` objective with no soft overlap, n = 0), Bai (1997, "Estimation of
a change point in multiple regression models", *Rev. Econ. Stat.* 79) shows
that, for each break,

    (δᵀQ₁δ)² / (δᵀΩ₁δ) · (k̂ − k₀)  ⇒  argmax_s V(s),

δ the change of the coefficient vector at the break, Q₁ and Ω₁ = σ₁²Q₁ the
second-moment matrix of the regressors and the long-run variance in the
segment before it, and V a two-sided Brownian motion with drift whose right
half has its own scale ξ = δᵀQ₂δ / δᵀQ₁δ and variance ratio φ = ξ·(σ₂/σ₁)².
Its distribution function has a closed form (Bai 1997, Appendix B), which is
strucchange's ``pargmaxV``. The interval is

    [k̂ − ⌈u⌉, k̂ − ⌊l⌋],   u, l the 1 − α/2 and α/2 quantiles of argmax V
                           times σ₁² / δᵀQ₁δ,

exactly as ``strucchange::confint.breakpointsfull`` (1.5-3) builds it:

* ``het_reg = True`` (default): Q₁, Q₂ from each segment's own regressors
  (``XᵀX / nᵢ``); ``False``: one Q, ``XᵀX / N`` over the whole run, ξ = 1.
* ``het_err = True`` (default): σᵢ² = RSSᵢ / nᵢ of each segment's own fit;
  ``False``: one σ² = RSS / N of the segmented fit.
* no interval (``None``) when P(argmax V ≤ 0) lies outside [α/2, 1 − α/2]
  (strucchange warns and returns NA there).

The ends are left as strucchange gives them (they may fall outside 1…N−1);
:func:`groupfit.inference.break_intervals` clips them for display.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import brentq
from scipy.special import log_ndtr

LOG_SQRT_2PI = 0.5 * np.log(2.0 * np.pi)


@dataclass(frozen=True)
class BreakInterval:
    """A confidence interval of one hard break, 1-based like the break.

    ``lower``/``upper`` are None where the interval cannot be computed.
    """

    brk: int
    lower: int | None
    upper: int | None
    level: float
    method: str

    def to_dict(self) -> dict:
        """The ``break_intervals`` entry of the JSON result (SPEC.md)."""
        return {"break": self.brk, "lower": self.lower, "upper": self.upper, "level": self.level, "method": self.method}

    def text(self) -> str:
        """``[lower, upper]`` or ``-``."""
        if self.lower is None or self.upper is None:
            return "-"
        return f"[{self.lower}, {self.upper}]"


def argmax_cdf(x: float, xi: float = 1.0, phi1: float = 1.0, phi2: float = 1.0) -> float:
    """P(argmax V ≤ x) for Bai's (1997) limiting process (strucchange's ``pargmaxV``).

    Parameters
    ----------
    x : float
        Point at which the distribution function is evaluated (standardised units).
    xi : float
        Ratio δᵀQ₂δ / δᵀQ₁δ of the regressor moments after and before the break.
    phi1, phi2 : float
        Error standard deviations before and after the break.
    """
    phi = xi * (phi2 / phi1) ** 2
    a = abs(float(x))
    if x < 0:
        frac = xi / phi
        return float(
            -np.exp(0.5 * np.log(a) - a / 8.0 - LOG_SQRT_2PI)
            - (phi / xi * (phi + 2 * xi) / (phi + xi))
            * np.exp(frac * (1 + frac) * a / 2.0 + log_ndtr(-(0.5 + frac) * np.sqrt(a)))
            + np.exp(np.log(a / 2.0 - 2.0 + (phi + 2 * xi) ** 2 / ((phi + xi) * xi)) + log_ndtr(-np.sqrt(a) / 2.0))
        )
    frac = xi**2 / phi
    first = np.sqrt(frac) * np.exp(0.5 * np.log(a) - frac * a / 8.0 - LOG_SQRT_2PI) if a > 0 else 0.0
    return float(
        1.0
        + first
        + (xi / phi * (2 * phi + xi) / (phi + xi))
        * np.exp((phi + xi) * a / 2.0 + log_ndtr(-(phi + xi / 2.0) / np.sqrt(phi) * np.sqrt(a)))
        - np.exp(
            np.log((2 * phi + xi) ** 2 / ((phi + xi) * phi) - 2.0 + frac * a / 2.0)
            + log_ndtr(-np.sqrt(frac) * np.sqrt(a) / 2.0)
        )
    )


def argmax_quantile(prob: float, xi: float = 1.0, phi1: float = 1.0, phi2: float = 1.0) -> float:
    """The ``prob`` quantile of argmax V (root of :func:`argmax_cdf`, bracketed as strucchange does)."""

    def gap(x: float) -> float:
        return argmax_cdf(x, xi, phi1, phi2) - prob

    if gap(0.0) < 0:
        end = 0.0
        while gap(end) < 0:
            end += 1000.0
        return brentq(gap, 0.0, end, xtol=1e-10, rtol=1e-12)
    end = 0.0
    while gap(end) > 0:
        end -= 1000.0
    return brentq(gap, end, 0.0, xtol=1e-10, rtol=1e-12)


def _segment_fit(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    residual = y - X @ coef
    return coef, float(residual @ residual)


def bai_intervals(
    X,
    y,
    breaks: Sequence[int],
    level: float = 0.95,
    *,
    het_reg: bool = True,
    het_err: bool = True,
) -> list[BreakInterval]:
    """Bai (1997) confidence intervals of least-squares break estimates.

    Parameters
    ----------
    X : array-like, shape (N, M)
        The regression design, intercept column included when there is one.
    y : array-like, shape (N,)
    breaks : sequence of int
        Break estimates, 1-based, each the last sample of its segment
        (strucchange's and groupfit's convention).
    level : float
        Confidence level.
    het_reg, het_err : bool
        Allow the regressors' second moments / the error variance to differ
        between segments (strucchange's defaults: both True).

    Returns
    -------
    list of BreakInterval
        One per break, ``method = "bai"``; ends None where strucchange gives NA.
    """
    X = np.asarray(X, dtype=float)
    if X.ndim == 1:
        X = X[:, None]
    y = np.asarray(y, dtype=float).ravel()
    n_obs = len(y)
    a2 = (1.0 - level) / 2.0
    edges = [0, *(int(b) for b in breaks), n_obs]
    segments = [slice(edges[j], edges[j + 1]) for j in range(len(edges) - 1)]
    fits = [_segment_fit(X[s], y[s]) for s in segments]
    rss_total = sum(rss for _, rss in fits)
    q_global = X.T @ X / n_obs
    sigma_global = rss_total / n_obs

    def moments(j: int) -> tuple[np.ndarray, float]:
        rows = edges[j + 1] - edges[j]
        q = X[segments[j]].T @ X[segments[j]] / rows if het_reg else q_global
        sigma2 = fits[j][1] / rows if het_err else sigma_global
        return q, sigma2

    result = []
    for j, brk in enumerate(edges[1:-1]):
        q1, sigma1 = moments(j)
        q2, sigma2 = moments(j + 1)
        delta = fits[j + 1][0] - fits[j][0]
        qprod1 = float(delta @ q1 @ delta)
        qprod2 = float(delta @ q2 @ delta)
        xi = qprod2 / qprod1 if het_reg else 1.0
        phi1, phi2 = np.sqrt(sigma1), np.sqrt(sigma2)
        with np.errstate(all="ignore"):
            p0 = argmax_cdf(0.0, xi, phi1, phi2)
        if not np.isfinite(p0) or p0 < a2 or p0 > 1.0 - a2:
            result.append(BreakInterval(brk, None, None, level, "bai"))
            continue
        with np.errstate(all="ignore"):
            upper = argmax_quantile(1.0 - a2, xi, phi1, phi2) * phi1**2 / qprod1
            lower = argmax_quantile(a2, xi, phi1, phi2) * phi1**2 / qprod1
        result.append(BreakInterval(brk, int(brk - np.ceil(upper)), int(brk - np.floor(lower)), level, "bai"))
    return result
