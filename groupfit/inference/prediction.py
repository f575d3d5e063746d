"""Prediction intervals of grouped models: per-group ordinary least-squares intervals.

Each soft group g is an ordinary least-squares fit on its own rows (n_g
samples, rank r_g), so a new sample x served by group g has the classical
interval

    ŷ ± t_{1−α/2, n_g − r_g} · s_g · sqrt(1 + xᵀ(A_gᵀA_g)⁺x),

with s_g² = RSS_g / (n_g − r_g) the residual variance of that group's fit on
its soft group (the overlap samples included, since they are part of the
fit). The overlap is handled by the serving rule: a sample is served by one
group only (:func:`groupfit.grouping.serving_group_index` offline, or the
run-time switching rule on another run), and its interval is that group's.
The global MLR is the one-group case and gives statsmodels' ``obs_ci``.

The intervals assume what OLS assumes inside each group: independent
errors of constant variance, and breaks taken as known (the interval does not
widen for the uncertainty of the break positions themselves).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy import stats

from groupfit.errors import InputError
from groupfit.objective import LSTSQ_RCOND, Standardiser


@dataclass
class GroupIntervalStats:
    """What a grouped model needs to give prediction intervals.

    Attributes
    ----------
    standardiser : Standardiser
        The centring and scaling of the modelling run (leverages are computed
        on the standardised design, which leaves them unchanged).
    bases : list of ndarray, shape (M, r_g)
        ``V_g S_g⁻¹`` from the SVD of each group's standardised design, so
        that a row's leverage is ``‖xᵀ V_g S_g⁻¹‖²``.
    sigma : ndarray, shape (n_groups,)
        Residual standard deviation of each group's fit (units of y).
    dof : ndarray, shape (n_groups,)
        Residual degrees of freedom ``n_g − r_g``.
    """

    standardiser: Standardiser
    bases: list[np.ndarray]
    sigma: np.ndarray
    dof: np.ndarray


def group_interval_stats(X, y, soft_groups: Sequence[Sequence[int]], *, fit_intercept: bool) -> GroupIntervalStats:
    """Residual variance, degrees of freedom and leverage basis of every soft group's fit.

    Parameters
    ----------
    X : array-like, shape (N, k)
    y : array-like, shape (N,)
    soft_groups : sequence of (first, last)
        1-based inclusive rows of each group's fit.
    fit_intercept : bool
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    std = Standardiser(X, y, fit_intercept=fit_intercept)
    A, t = std.design(X), std.target(y)
    bases, sigma, dof = [], [], []
    for first, last in soft_groups:
        rows = slice(int(first) - 1, int(last))
        u, s, vt = np.linalg.svd(A[rows], full_matrices=False)
        keep = s > LSTSQ_RCOND * (s[0] if s.size else 0.0)
        u, s, vt = u[:, keep], s[keep], vt[keep]
        residual = t[rows] - u @ (u.T @ t[rows])
        rank = int(keep.sum())
        freedom = (int(last) - int(first) + 1) - rank
        bases.append(vt.T / s)
        dof.append(freedom)
        sigma.append(np.sqrt(residual @ residual / freedom) * std.y_scale if freedom > 0 else np.inf)
    return GroupIntervalStats(std, bases, np.asarray(sigma, dtype=float), np.asarray(dof))


def resolve_level(level: float | None = None, alpha: float | None = None) -> float:
    """The confidence level from ``level`` or ``alpha = 1 − level`` (default 0.95)."""
    if level is not None and alpha is not None and not np.isclose(level, 1.0 - alpha):
        raise InputError(f"level = {level:g} and alpha = {alpha:g} disagree; give one of them")
    if level is None:
        level = 0.95 if alpha is None else 1.0 - alpha
    if not 0.0 < level < 1.0:
        raise InputError(f"level = {level:g} must lie strictly between 0 and 1")
    return float(level)


def prediction_bounds(
    interval_stats: GroupIntervalStats, X, groups, prediction, level: float = 0.95
) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper prediction bounds of samples served by the given groups.

    Parameters
    ----------
    interval_stats : GroupIntervalStats
    X : array-like, shape (n, k)
        Temperatures of the samples.
    groups : array-like of int, shape (n,)
        0-based group serving each sample.
    prediction : array-like, shape (n,)
        The model's predictions of those samples.
    level : float
        Confidence level of the interval.
    """
    X = np.asarray(X, dtype=float)
    groups = np.asarray(groups, dtype=int)
    prediction = np.asarray(prediction, dtype=float)
    design = interval_stats.standardiser.design(X)
    half = np.empty(len(prediction))
    for g in np.unique(groups):
        rows = groups == g
        leverage = np.sum((design[rows] @ interval_stats.bases[g]) ** 2, axis=1)
        dof = interval_stats.dof[g]
        quantile = stats.t.ppf(0.5 + level / 2.0, dof) if dof > 0 else np.inf
        half[rows] = quantile * interval_stats.sigma[g] * np.sqrt(1.0 + leverage)
    return prediction - half, prediction + half


def estimator_bounds(estimator, X, groups, prediction, level=None, alpha=None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`prediction_bounds` of a fitted :class:`~groupfit.models.grouped.GroupedRegressor`."""
    interval_stats = getattr(estimator, "interval_stats_", None)
    if interval_stats is None:
        raise InputError(
            "this model has no prediction-interval statistics (it was loaded from a model file); "
            "refit it on its modelling run to get intervals"
        )
    return prediction_bounds(interval_stats, X, groups, prediction, resolve_level(level, alpha))


def band_for(estimator, X, prediction, groups=None, level: float = 0.95) -> tuple[np.ndarray, np.ndarray] | None:
    """Prediction band of a run served by ``groups`` (default: by sample index); None without statistics."""
    if getattr(estimator, "interval_stats_", None) is None:
        return None
    if groups is None:
        groups = estimator.serving_groups(len(np.asarray(X)))
    return prediction_bounds(estimator.interval_stats_, X, groups, prediction, level)
