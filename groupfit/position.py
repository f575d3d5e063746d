"""Position-dependent models: runs measured at several axis positions, their fit, order selection and tables.

A feed axis' thermal error depends on where the axis is (docs/position.md):

    E(P, T) = K0(T) + c1(T)·d + … + c_K(T)·d^K,   d = P − P0 (mm),

each ``c_k(T)`` linear in the model's inputs (per group for a grouped model).
Order 1 is SINUMERIK's ``K0 + tanβ·(P − P0)``.

Shops measure it as ISO 230-3 style check runs: every 20 min the axis visits
a set of positions and the error is read at each. Such a run is a *long* table
(one row per check run and position: time, position, temperatures, error) or
a *wide* one (one row per check run, one error column per position named
``err_P<mm>``, e.g. ``err_P0100``, ``err_P-50``, ``err_P250.5``). A long table
holds several rows per time stamp, so the run's sampling is checked on the
check runs (its distinct time stamps), not on its rows: :func:`load_position_run`
returns the run of check runs (one row each: the temperatures and the mean
error over the positions, what the switching rule and the break search count)
and the rows of every position.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.data import (
    DEFAULT_ERROR,
    DEFAULT_TIME,
    ERROR_LIMIT_UM,
    PERIOD_TOLERANCE,
    TEMP_RANGE_C,
    Run,
    load_run,
    numeric_column,
    read_table,
    refuse_beyond,
)
from groupfit.default_columns import default_temperature_columns, length_unit, length_unit_named
from groupfit.errors import InputError
from groupfit.export.table import position_coefficients
from groupfit.model import MAX_POSITION_ORDER, DeadBand, ModelFile, Position

WIDE_PREFIX = "err_P"
WIDE_COLUMN = re.compile(r"^err_P(-?\d+(?:\.\d+)?)$")
"""A wide table's error column at one position: ``err_P`` and the position in mm (``err_P0100`` = 100 mm)."""


@dataclass(frozen=True)
class PositionRun:
    """A run measured at several axis positions.

    Attributes
    ----------
    run : Run
        One row per check run (time stamp): the temperatures as read at its
        first row, the error the mean over its positions.
    check : ndarray of int, shape (R,)
        0-based check run of every row.
    position : ndarray, shape (R,)
        Axis position of every row, mm.
    error : ndarray, shape (R,)
        Thermal error of every row, µm.
    column : str
        Name of the position column.
    """

    run: Run
    check: np.ndarray
    position: np.ndarray
    error: np.ndarray
    column: str

    @property
    def positions(self) -> np.ndarray:
        """The distinct positions measured, mm, ascending."""
        return np.unique(self.position)

    @property
    def travel(self) -> tuple[float, float]:
        return float(self.position.min()), float(self.position.max())

    def inputs(self) -> np.ndarray:
        """The model's inputs of every row (those of its check run)."""
        return self.run.temps[self.check]


MAX_POSITION_MM = 1e6
"""Largest plausible axis position in mm (a kilometre): a larger one is a corrupt cell."""


def wide_columns(frame: pd.DataFrame, label: str = "the wide table") -> dict[str, float]:
    """The wide table's error columns and their positions (mm), in column order.

    A column that starts with ``err_P`` but names no position, and two columns of one position
    (``err_P100`` beside ``err_P0100``), are refused.
    """
    columns: dict[str, float] = {}
    for c in map(str, frame.columns):
        if not c.startswith(WIDE_PREFIX):
            continue
        match = WIDE_COLUMN.match(c)
        if match is None:
            raise InputError(
                f"{label}: column '{c}' starts with {WIDE_PREFIX} but names no position in mm (e.g. "
                f"{WIDE_PREFIX}0100); rename it"
            )
        twin = next((name for name, mm in columns.items() if mm == float(match.group(1))), None)
        if twin is not None:
            raise InputError(f"{label}: columns '{twin}' and '{c}' are both at {float(match.group(1)):g} mm; keep one")
        columns[c] = float(match.group(1))
    return columns


def wide_to_long(frame: pd.DataFrame, position: str, error: str = DEFAULT_ERROR) -> pd.DataFrame:
    """A wide table (one ``err_P<mm>`` column per position) as a long one: one row per check run and position.

    Every other column is repeated on each of a check run's rows; the rows
    come check run by check run, positions in column order. A position whose
    error is missing (empty cell) is left out of that check run.
    """
    columns = wide_columns(frame)
    if not columns:
        raise InputError(f"no error columns named {WIDE_PREFIX}<mm> (e.g. {WIDE_PREFIX}0100) in the wide table")
    for name in (position, error):
        if name in frame.columns:
            raise InputError(f"a wide table must not have a column '{name}' besides its {WIDE_PREFIX}<mm> columns")
    others = [c for c in frame.columns if str(c) not in columns]
    parts = []
    for name, mm in columns.items():
        part = frame[others].copy()
        part[position] = mm
        part[error] = frame[name]
        part["_row"] = np.arange(len(frame))
        part["_col"] = len(parts)
        parts.append(part)
    long = pd.concat(parts, ignore_index=True).sort_values(["_row", "_col"], kind="stable")
    long = long[long[error].notna()].drop(columns=["_row", "_col"]).reset_index(drop=True)
    return long


def refuse_implausible_errors(values: np.ndarray, column: str, label: str, limit: float | None) -> None:
    """Refuse the first error reading (µm, rows of the file counted from 1) beyond ±``limit``; none when None."""
    beyond = np.flatnonzero(np.abs(values) > limit) if limit is not None else []
    if len(beyond):
        row = int(beyond[0])
        raise InputError(
            f"{label}: row {row + 1}, column '{column}': {values[row]:g} µm is beyond the plausible ±{limit:g} µm "
            f"({len(beyond)} such value(s)); repair the data, or widen the range with --range-error MAX"
        )


METRES = re.compile(r"(?:^|[\s_\[(/（［])m\s*[\])）］]?\s*$")
"""A name that ends in metres (``probe_x_m``, ``X [m]``)."""


def millimetres_per_unit(column: str) -> float:
    """The millimetres of one unit of a position column by its name: metres (``probe_x_m``, ``X [m]``) ×1000, a
    unit of length (``X [µm]``, ``X [1/100 mm]``) by :func:`groupfit.default_columns.length_unit`, else mm."""
    if METRES.search(str(column)):
        return 1000.0
    if length_unit_named(column) is None:
        return 1.0
    return length_unit(column)[1] / 1000.0


def position_unit_notes(column: str, label: str) -> tuple[str, ...]:
    """The note of a position column read in another unit than mm (none for one in mm)."""
    scale = millimetres_per_unit(column)
    if scale == 1.0:
        return ()
    return (f"{label}: position column '{column}' is in another unit than mm by its name: read ×{scale:g} as mm",)


def load_position_run(
    source,
    position: str,
    *,
    temps: Sequence[str] | None = None,
    time: str = DEFAULT_TIME,
    error: str = DEFAULT_ERROR,
    temp_range: tuple[float, float] | None = TEMP_RANGE_C,
    error_limit: float | None = ERROR_LIMIT_UM,
    name: str | None = None,
    period_tolerance: float = PERIOD_TOLERANCE,
    resample: float | None = None,
) -> PositionRun:
    """Read a long or wide position run (module docstring) and check it.

    The check runs (distinct time stamps) must be uniformly sampled, as a
    run's samples are, within ``period_tolerance``; the rows of one check run
    may come in any position order. Missing or non-numeric positions are
    refused with the row, and so is ``resample``: the rows of one check run
    share its time stamp already, and averaging over a period would mix the
    positions.
    """
    frame, run_name, label = read_table(source, name)
    if resample is not None:
        raise InputError(
            f"{label}: --resample {resample:g} averages the readings of each period, which would mix a check run's "
            "positions; a position run is one check run per time stamp: leave --resample out"
        )
    inputs = temps if temps is not None else default_temperature_columns(frame.columns, exclude=(time, error))
    if position in (time, error):
        role = "time" if position == time else "thermal error"
        raise InputError(
            f"{label}: --position '{position}' is the run's {role}; the axis position needs a column of its own"
        )
    if position in inputs:
        raise InputError(
            f"{label}: --position '{position}' is also a temperature input; the axis position needs a column of "
            "its own (name the inputs with --temps)"
        )
    scale = millimetres_per_unit(position) if position in frame.columns else 1.0  # wide: err_P<mm> gives mm
    if position not in frame.columns:
        if wide_columns(frame, label):
            for column in wide_columns(frame):
                values = numeric_column(frame, column, label, allow_nonfinite=True)
                refuse_implausible_errors(values, column, label, error_limit)
            frame = wide_to_long(frame, position, error)
        else:
            raise InputError(
                f"{label}: position column '{position}' not found, and no wide error columns "
                f"({WIDE_PREFIX}<mm>). The columns are: {', '.join(map(str, frame.columns))}"
            )
    positions = finite_column(frame, position, label, "axis position") * scale
    refuse_beyond(positions, MAX_POSITION_MM, position, label, "mm is not a plausible axis position")
    times = numeric_column(frame, time, label, allow_nonfinite=False)
    error_values = finite_column(frame, error, label, "thermal error")
    refuse_implausible_errors(error_values, error, label, error_limit)
    order = np.argsort(times, kind="stable")
    frame = frame.iloc[order].reset_index(drop=True)
    positions, times, error_values = positions[order], times[order], error_values[order]
    stamps, check = np.unique(times, return_inverse=True)
    if len(np.unique(positions)) < 2:
        raise InputError(f"{label}: column '{position}' holds one position only; a position model needs several")
    first = np.searchsorted(times, stamps)
    checks = frame.iloc[first].reset_index(drop=True)
    checks[error] = np.bincount(check, weights=error_values) / np.bincount(check)
    checks = checks.drop(columns=[position])
    run = load_run(
        checks,
        temps=temps,
        time=time,
        error=error,
        name=run_name,
        temp_range=temp_range,
        error_limit=error_limit,
        period_tolerance=period_tolerance,
    )
    in_mm = position_unit_notes(position, label) if scale != 1.0 else ()
    run = replace(run, source=f"{label} (check runs)", notes=run.notes + in_mm)
    return PositionRun(run=run, check=check, position=positions, error=error_values, column=position)


def finite_column(frame: pd.DataFrame, column: str, label: str, what: str) -> np.ndarray:
    """A column of a table of check runs, refusing an empty or non-finite cell with its row: every row is one
    position's reading of its check run, which nothing fills in (``--resample`` would mix the positions)."""
    values = numeric_column(frame, column, label, allow_nonfinite=True)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        cell = "empty" if np.isnan(values[bad[0]]) else f"{values[bad[0]]:g}"
        raise InputError(
            f"{label}: row {bad[0] + 1}, column '{column}' is {cell} ({bad.size} such row(s)): each row of a check "
            f"run needs its {what}; repair or drop those rows"
        )
    return values


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
