"""Tables of check runs at several axis positions: a long or a wide table read as a run of check runs and its rows.

Shops measure a feed axis as ISO 230-3 style check runs: every 20 min the
axis visits a set of positions and the error is read at each (docs/position.md).
Such a run is a *long* table (one row per check run and position: time,
position, temperatures, error) or a *wide* one (one row per check run, one
error column per position named ``err_P<mm>``, e.g. ``err_P0100``,
``err_P-50``, ``err_P250.5``). A long table holds several rows per time stamp,
so the run's sampling is checked on the check runs (its distinct time stamps),
not on its rows: :func:`load_position_run` returns the run of check runs (one
row each: the temperatures and the mean error over the positions, what the
switching rule and the break search count) and the rows of every position.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
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
from groupfit.default_columns import WIDE_PREFIX, default_temperature_columns, length_unit, length_unit_named
from groupfit.error_scale import with_scaled_error
from groupfit.errors import InputError

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
    rows : DataFrame or None
        The table's rows as read (a wide table in the long form), in the order
        of ``check``: what each row's own readings are taken from.
    file_row : ndarray of int or None
        The row of the file (0-based, the header not counted) each row was read
        from, to name it in messages.
    """

    run: Run
    check: np.ndarray
    position: np.ndarray
    error: np.ndarray
    column: str
    rows: pd.DataFrame | None = field(default=None, repr=False, compare=False)
    file_row: np.ndarray | None = field(default=None, repr=False, compare=False)

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
    positions. An error column in another unit than µm by its name
    (``error_mm``) is read in µm on every row, as :func:`groupfit.data.load_run`
    reads it, and so is ``COLUMN*K`` (column ``COLUMN`` ×K); so are a wide
    table's ``err_P<mm>`` columns, in the unit (or ×K) of ``error``'s name.
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
    if position in frame.columns:  # a long table: --error 'COLUMN*K' reads COLUMN ×K, as on a stream
        frame = with_scaled_error(frame, error, label)
    scale = millimetres_per_unit(position) if position in frame.columns else 1.0  # wide: err_P<mm> gives mm
    per_um = length_unit(error)[1]  # an error in mm or nm by its name is read in µm, as a stream's is
    where = f"column '{position}'" if position in frame.columns else "its error columns (err_P<mm>)"
    frame, file_row = long_form(frame, position, error, label, error_limit, per_um)
    positions = finite_column(frame, position, label, "axis position") * scale
    refuse_beyond(positions, MAX_POSITION_MM, position, label, "mm is not a plausible axis position")
    times = numeric_column(frame, time, label, allow_nonfinite=False)
    logged = finite_column(frame, error, label, "thermal error")
    error_values = logged * per_um
    refuse_implausible_errors(error_values, error, label, error_limit)
    order = np.argsort(times, kind="stable")
    frame = frame.iloc[order].reset_index(drop=True)
    positions, times, error_values, logged = positions[order], times[order], error_values[order], logged[order]
    file_row = file_row[order]
    stamps, check = np.unique(times, return_inverse=True)
    if len(np.unique(positions)) < 2:
        raise InputError(f"{label}: {where} hold(s) one position only; a position model needs several")
    first = np.searchsorted(times, stamps)
    checks = frame.iloc[first].reset_index(drop=True)
    checks[error] = np.bincount(check, weights=logged) / np.bincount(check)  # as logged: load_run reads its unit
    checks = checks.drop(columns=[position])
    refuse_unread_inputs(checks, inputs, label, file_row[first])
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
    return PositionRun(
        run=run, check=check, position=positions, error=error_values, column=position, rows=frame, file_row=file_row
    )


def long_form(
    frame: pd.DataFrame, position: str, error: str, label: str, error_limit: float | None, per_um: float
) -> tuple[pd.DataFrame, np.ndarray]:
    """The table in the long form (a wide one converted, its ``err_P<mm>`` cells read ×``per_um`` as µm and
    refused beyond ``error_limit`` with their row), and the row of the file each row was read from (0-based)."""
    if position in frame.columns:
        return frame, np.arange(len(frame))
    columns = wide_columns(frame, label)
    if not columns:
        raise InputError(
            f"{label}: position column '{position}' not found, and no wide error columns "
            f"({WIDE_PREFIX}<mm>). The columns are: {', '.join(map(str, frame.columns))}"
        )
    for column in columns:
        values = numeric_column(frame, column, label, allow_nonfinite=True)
        refuse_implausible_errors(values * per_um, column, label, error_limit)
    read = frame[list(columns)].notna().to_numpy()  # wide_to_long's rows: file row by file row, columns in order
    return wide_to_long(frame, position, error), np.nonzero(read)[0]


def refuse_unread_inputs(checks: pd.DataFrame, temps, label: str, rows: np.ndarray) -> None:
    """Refuse a check run whose first row, where its inputs are read, lacks one, naming that row of the file
    (``rows``: each check run's first row, 0-based): nothing fills it in (``--resample`` would mix the positions)."""
    for column in temps:
        if column not in checks.columns:
            continue
        values = numeric_column(checks, column, label, allow_nonfinite=True)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise InputError(
                f"{label}: row {int(rows[bad[0]]) + 1}, column '{column}' is empty or no number ({bad.size} check "
                "run(s) so): a check run's inputs are read on its first row; repair or drop that row"
            )


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


__all__ = [
    "MAX_POSITION_MM",
    "PositionRun",
    "WIDE_PREFIX",
    "finite_column",
    "load_position_run",
    "millimetres_per_unit",
    "position_unit_notes",
    "refuse_implausible_errors",
    "wide_columns",
    "wide_to_long",
]
