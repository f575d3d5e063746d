"""Position-dependent models: runs measured at several axis positions, their fit, order selection and tables.

A feed axis' thermal error depends on where the axis is (docs/position.md):

    E(P, T) = K0(T) + c1(T)·d + … + c_K(T)·d^K,   d = P − P0 (mm),

each ``c_k(T)`` linear in the model's inputs (per group for a grouped model).
Order 1 is SINUMERIK's ``K0 + tanβ·(P − P0)``.

The tables of check runs at several positions that such a model is fitted on
are read by :mod:`groupfit.position_table`.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from groupfit.errors import InputError
from groupfit.export.table import position_coefficients
from groupfit.model import MAX_POSITION_ORDER, DeadBand, ModelFile, Position
from groupfit.position_table import MAX_POSITION_MM as MAX_POSITION_MM
from groupfit.position_table import WIDE_PREFIX as WIDE_PREFIX
from groupfit.position_table import PositionRun as PositionRun
from groupfit.position_table import finite_column as finite_column
from groupfit.position_table import load_position_run as load_position_run
from groupfit.position_table import millimetres_per_unit as millimetres_per_unit
from groupfit.position_table import position_unit_notes as position_unit_notes
from groupfit.position_table import wide_columns as wide_columns
from groupfit.position_table import wide_to_long as wide_to_long

# --------------------------------------------------------------------- the fit


def design(inputs: np.ndarray, d: np.ndarray, order: int, *, intercept: bool = True) -> np.ndarray:
    """Columns of the least-squares fit: for k = 0…order, ``d^k`` times (1 and) every input."""
    inputs = np.asarray(inputs, dtype=float)
    base = np.column_stack([np.ones(len(inputs)), inputs]) if intercept else inputs
    return np.column_stack([base * (d**k)[:, None] for k in range(order + 1)])


def fit_blocks(inputs, d, error, order: int, *, intercept: bool = True) -> np.ndarray:
    """Least-squares coefficients, shape (order + 1, M (+1)): row k the coefficients of ``c_k`` (row 0: K0)."""
    matrix = design(inputs, d, order, intercept=intercept)
    scale = np.maximum(np.abs(matrix).max(axis=0), 1e-300)
    solution, *_ = np.linalg.lstsq(matrix / scale, np.asarray(error, dtype=float), rcond=None)
    return (solution / scale).reshape(order + 1, -1)


def predict_blocks(blocks: np.ndarray, inputs, d, *, intercept: bool = True) -> np.ndarray:
    return design(inputs, d, blocks.shape[0] - 1, intercept=intercept) @ blocks.ravel()


def choose_p0(prun: PositionRun, text: str | float | None) -> float:
    """P0: a number of mm, or ``middle`` (default), ``min`` or ``max`` of the measured travel."""
    low, high = prun.travel
    if text is None or text == "middle":
        return 0.5 * (low + high)
    if text == "min":
        return low
    if text == "max":
        return high
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(f"--position-ref {text!r}: a position in mm, or middle, min or max") from None
    if not math.isfinite(value):
        raise InputError(f"--position-ref {text!r}: a finite position in mm")
    if not low - (high - low) <= value <= high + (high - low):
        raise InputError(
            f"--position-ref {value:g}: far outside the measured travel {low:g}…{high:g} mm (more than its length); "
            "give a position near the travel, or middle, min or max"
        )
    return value


def cross_validate_order(
    prun: PositionRun, max_order: int = 4, p0: float | None = None, *, intercept: bool = True
) -> dict:
    """Out-of-sample RMS of every order 1…max_order, the folds being the held-out positions (a global fit).

    Each measured position in turn is left out; the model is fitted on the
    others and scored at it. Returns ``{"orders", "rms_um", "order"}``, the
    chosen order being the smallest whose RMS is within 5 % of the best
    (fewer terms when the data cannot tell them apart).
    """
    positions = prun.positions
    max_order = min(max_order, MAX_POSITION_ORDER, len(positions) - 2)
    if max_order < 1:
        raise InputError(f"{len(positions)} positions: order selection needs at least 3")
    p0 = 0.5 * sum(prun.travel) if p0 is None else p0
    inputs, d = prun.inputs(), prun.position - p0
    rms = []
    for order in range(1, max_order + 1):
        residuals = np.empty(len(d))
        for held in positions:
            out = prun.position == held
            blocks = fit_blocks(inputs[~out], d[~out], prun.error[~out], order, intercept=intercept)
            residuals[out] = prun.error[out] - predict_blocks(blocks, inputs[out], d[out], intercept=intercept)
        rms.append(float(np.sqrt(np.mean(residuals**2))))
    best = min(rms)
    chosen = next(k for k, value in enumerate(rms, start=1) if value <= 1.05 * best)
    return {"orders": list(range(1, max_order + 1)), "rms_um": rms, "order": chosen, "folds": "held-out positions"}


TABLE_ORDERS = (1, 2, 3, 4, 5)
"""The orders of the per-order residual table (seed 004 compares orders 1–5 and chooses 4)."""


def residual_by_order(model: ModelFile, prun: PositionRun, p0: float, orders=TABLE_ORDERS) -> list[dict]:
    """Max and mean |residual| (µm) over every row of the position fit of each order (seed 004's table).

    Each order is fitted as :func:`with_position` fits it (per soft group, on
    the rows of its check runs) and scored on the rows each group serves;
    orders the positions cannot carry (``order ≥`` number of positions) are
    left out.
    """
    inputs, d = prun.inputs(), prun.position - p0
    serving = model.serving_groups(prun.run.n_samples)[prun.check]
    table = []
    for order in orders:
        if not 1 <= order < min(len(prun.positions), MAX_POSITION_ORDER + 1):
            continue
        residual = np.empty(len(d))
        for g, (first, last) in enumerate(model.soft_groups):
            rows = (prun.check >= first - 1) & (prun.check <= last - 1)
            blocks = fit_blocks(inputs[rows], d[rows], prun.error[rows], order, intercept=model.intercept)
            served = serving == g
            residual[served] = prun.error[served] - predict_blocks(
                blocks, inputs[served], d[served], intercept=model.intercept
            )
        table.append(
            {
                "order": int(order),
                "max_um": float(np.max(np.abs(residual))),
                "mean_um": float(np.mean(np.abs(residual))),
                "rms_um": float(np.sqrt(np.mean(residual**2))),
            }
        )
    return table


def with_position(
    model: ModelFile,
    prun: PositionRun,
    order: int,
    p0: float,
    *,
    dead_band: DeadBand | None = None,
) -> ModelFile:
    """The grouped model ``model`` (fitted on ``prun.run``) refitted with position terms on every row.

    The groups, breaks and switching rule stay those of the check runs; each
    soft group's ``K0`` and ``c_1 … c_order`` are refitted by least squares on
    the rows of its check runs. The clamp covers the largest predicted error
    over the rows and the travel's ends, and the rate limit lets the output
    cross the whole travel's spread of the error within one sample (the axis
    may move from end to end between two samples).
    """
    if not 1 <= order <= MAX_POSITION_ORDER:
        raise InputError(f"--position-order {order}: choose 1…{MAX_POSITION_ORDER} or auto")
    if dead_band is not None and dead_band.reference in model.temps:
        raise InputError(
            f"--dead-band-ref '{dead_band.reference}': a model input; the dead band compares the inputs with a "
            "sensor of its own (the ambient air, e.g. T_amb)"
        )
    n_positions = len(prun.positions)
    if order >= n_positions:
        raise InputError(f"--position-order {order}: {n_positions} positions fit at most order {n_positions - 1}")
    inputs, d = prun.inputs(), prun.position - p0
    rows = []
    k0 = []
    for first, last in model.soft_groups:
        mask = (prun.check >= first - 1) & (prun.check <= last - 1)
        blocks = fit_blocks(inputs[mask], d[mask], prun.error[mask], order, intercept=model.intercept)
        k0.append(tuple(float(v) for v in blocks[0]))
        rows.append(tuple(tuple(float(v) for v in block) for block in blocks[1:]))
    position = Position(
        column=prun.column, p0_mm=float(p0), order=int(order), travel_mm=prun.travel, coefficients=tuple(rows)
    )
    fitted = model.replace(coefficients=tuple(k0), position=position, dead_band=dead_band)
    groups = fitted.serving_groups(prun.run.n_samples)[prun.check]
    states = position_coefficients(fitted, prun.run.temps, fitted.serving_groups(prun.run.n_samples))
    ranges = tuple((float(lo), float(hi)) for lo, hi in zip(states.min(axis=0), states.max(axis=0)))
    fitted = fitted.replace(position=replace(position, coefficient_ranges=ranges))
    prediction = fitted.predict_position(inputs, prun.position, groups)
    residuals = prun.error - prediction
    low, high = prun.travel
    ends = np.concatenate(
        [fitted.predict_position(inputs, np.full(len(d), end), groups) for end in (low, high)] + [prediction]
    )
    clamp = max(float(model.switching.comp_max_um or 0.0), math.ceil(1.5 * float(np.max(np.abs(ends)))))
    spread = 0.0
    for c in range(prun.run.n_samples):
        at = prun.check == c
        spread = max(spread, float(np.ptp(prediction[at])) if at.any() else 0.0)
    rate = max(
        float(model.switching.rate_limit_um or 0.0),
        math.ceil(10.0 * (float(model.switching.rate_limit_um or 0.0) + spread)) / 10.0,
    )
    switching = model.switching.with_rule(
        {"comp_min_um": -float(clamp), "comp_max_um": float(clamp), "rate_limit_um": rate}
    )
    training = dict(model.training or {})
    training.update(
        position_rms_um=float(np.sqrt(np.mean(residuals**2))), position_max_um=float(np.max(np.abs(residuals)))
    )
    return fitted.replace(switching=switching, training=training)


__all__ = [
    "PositionRun",
    "WIDE_PREFIX",
    "choose_p0",
    "cross_validate_order",
    "design",
    "fit_blocks",
    "load_position_run",
    "residual_by_order",
    "wide_to_long",
    "with_position",
]
