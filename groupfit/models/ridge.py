"""Ridge coefficients for a global model whose many inputs are collinear.

Sixteen temperature sensors on one headstock move together; least squares
then spreads the error over large coefficients of opposite sign that cancel
on the modelling run and not on the next one. A ridge penalty keeps them
small. The penalty is put on each input *scaled to unit spread* over the
modelling data (its standard deviation with an intercept, its RMS without),
and grows with the number of samples fitted:

    minimise  Σ (y − ŷ)²  +  alpha · m · Σⱼ (βⱼ · sⱼ)²,

so ``alpha`` has the same meaning on a short run as on a long one, on °C as
on K, and the intercept is never shrunk. ``alpha = 0`` is least squares.

The penalty is chosen, like everything that is meant to hold on the next
run, on held-out operating conditions or runs (:func:`choose_ridge_alpha`).
The coefficient vector it gives is an ordinary one: the run-time routine and
every export are unchanged.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from groupfit.errors import InputError
from groupfit.model_checks import MAX_RIDGE_ALPHA

RIDGE_GRID = (0.0, 1e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 1e-1, 3e-1, 1.0)
"""The penalties ``--ridge auto`` tries."""


def input_spreads(X: np.ndarray, *, fit_intercept: bool) -> np.ndarray:
    """Each column's spread sⱼ: standard deviation with an intercept, RMS without (0 for a constant with one)."""
    X = np.asarray(X, dtype=float)
    if fit_intercept:
        return X.std(axis=0)
    return np.sqrt(np.mean(X**2, axis=0))


def penalty_diagonal(spreads: np.ndarray, alpha: float, n_rows: int, *, fit_intercept: bool) -> np.ndarray:
    """The diagonal of the penalty on the design ``[1, X]`` (or ``X``): α·m·sⱼ², none on the constant."""
    slopes = alpha * n_rows * np.asarray(spreads, dtype=float) ** 2
    return np.r_[0.0, slopes] if fit_intercept else slopes


def ridge_solve(A: np.ndarray, y: np.ndarray, penalty: np.ndarray) -> np.ndarray:
    """Coefficients minimising ``‖y − A·c‖² + Σ penaltyⱼ·cⱼ²`` (minimum-norm least squares when all are 0)."""
    penalty = np.asarray(penalty, dtype=float)
    if not np.any(penalty > 0):
        coef, *_ = np.linalg.lstsq(A, y, rcond=1e-6)
        return coef
    norms = np.linalg.norm(A, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    Z = A / norms
    gram = Z.T @ Z + np.diag(penalty / norms**2)
    coef, *_ = np.linalg.lstsq(gram, Z.T @ y, rcond=1e-13)
    return coef / norms


def check_ridge_alpha(alpha: float) -> float:
    """``alpha`` as a float, or InputError naming it."""
    try:
        value = float(alpha)
    except (TypeError, ValueError):
        raise InputError(f"ridge alpha {alpha!r}: give a number ≥ 0 or 'auto'") from None
    if not (np.isfinite(value) and 0.0 <= value <= MAX_RIDGE_ALPHA):
        raise InputError(f"ridge alpha {alpha!r}: give a number in [0, {MAX_RIDGE_ALPHA:g}] or 'auto'")
    return value


def held_out_sse(
    X: np.ndarray,
    y: np.ndarray,
    splits: Sequence[tuple[np.ndarray, np.ndarray]],
    alpha: float,
    *,
    fit_intercept: bool = True,
) -> np.ndarray:
    """Held-out squared error per fold of the ridge fit with penalty ``alpha`` on each fold's complement.

    The spreads sⱼ are those of all of ``X``: one fixed penalty, refitted per fold.
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float)
    A = np.column_stack([np.ones(len(X)), X]) if fit_intercept else X
    spreads = input_spreads(X, fit_intercept=fit_intercept)
    sse = np.empty(len(splits))
    for k, (train, test) in enumerate(splits):
        penalty = penalty_diagonal(spreads, alpha, len(train), fit_intercept=fit_intercept)
        coef = ridge_solve(A[train], y[train], penalty)
        error = y[test] - A[test] @ coef
        sse[k] = float(error @ error)
    return sse


def choose_ridge_alpha(
    X: np.ndarray,
    y: np.ndarray,
    splits: Sequence[tuple[np.ndarray, np.ndarray]],
    *,
    fit_intercept: bool = True,
    grid: Sequence[float] = RIDGE_GRID,
) -> tuple[float, list[dict[str, float]]]:
    """The penalty of ``grid`` with the least held-out error, and the held-out RMS of each (µm).

    Ties go to the smaller penalty (least squares when nothing is gained).
    """
    n_test = sum(len(test) for _, test in splits)
    table = []
    for alpha in grid:
        sse = held_out_sse(X, y, splits, alpha, fit_intercept=fit_intercept)
        table.append({"alpha": float(alpha), "held_out_rms_um": float(np.sqrt(sse.sum() / n_test))})
    best = min(table, key=lambda row: (row["held_out_rms_um"], row["alpha"]))
    return best["alpha"], table
