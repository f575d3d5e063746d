"""A run's value columns read as numbers and checked: the temperature inputs, the error, their plausible ranges.

:func:`groupfit.data.load_run` reads a log through these; every refusal names
the file, the row and the column.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import NamedTuple, Sequence

import numpy as np
import pandas as pd

from groupfit.columns import renamed_from
from groupfit.default_columns import (
    DEFAULT_ERROR,
    DEFAULT_TIME,
    ambient_columns,
    default_temperature_columns,
    factored_length_unit,
    length_unit,
    named_length_unit,
    scaled_name,
    temperature_like_columns,
)
from groupfit.error_start import from_start, is_from_start
from groupfit.errors import InputError
from groupfit.gap_advice import log_readings, log_rows, missing_advice, missing_count, resampled_row
from groupfit.textencoding import misread
from groupfit.twin_columns import twin_note

TEMP_RANGE_C = (-50.0, 500.0)
"""Plausible temperature readings (°C) of the sensors of a machine; anything outside is refused.

Wider than any machine shop (coolant, bearings and motors stay well inside
it) and than the hot end of a 3-D printer (200-300 °C, logged as ``T0`` by
its firmware), and narrower than the overflow values a broken logger writes
(1e300, 9999, 3276.7, a missing sensor read as −273 or 850 °C).
``--range-temp=LOW,HIGH`` (or ``[data] temp_range``) sets another.
"""
NO_READING = re.compile(
    r"[-*?]+|n\.?a\.?|none|null|ovl|[-+]?ol|over(?:flow)?|err(?:or)?\.?|fault"
    r"|#[a-z]+(?:/[a-z0-9]+)?[!?]?|[-+]?1\.#(?:inf|qnan|snan|ind)0*",
    re.IGNORECASE,
)
"""Cells a logger writes for a reading it did not take (``---``, ``n.a.``, ``OVL``, ``Err``, a multimeter's
``OL``), a spreadsheet's error values (``#N/A``, ``#NV``, ``#VALUE!``, ``#DIV/0!``) and an old C library's
``1.#INF`` and ``1.#QNAN``: read as empty."""
ERROR_LIMIT_UM = 1.0e5
"""Largest plausible thermal error (µm): 0.1 m. ``--range-error MAX`` (or ``[data] error_limit``) widens it."""


SIGNAL_UNIT = re.compile(
    r"(?:[\[(]\s*(v|vdc|vac|mv|ma|a|counts?|digits?|inc)\s*[\])]|[_\s](vdc|vac|mv|volts?))\s*$", re.IGNORECASE
)
"""A transducer's signal unit at the end of a name (``105 (VDC)``, ``probe [mV]``, ``disp_mV``): not a length."""


SMALLEST_ERROR_SPAN_UM = 0.1
"""An error that spans less than this over a whole run (µm) is below what thermal drift and a displacement sensor
show: a column in mm (or m) whose name gives no unit, read as µm, looks like this."""
LARGEST_ERROR_SPAN_UM = 1000.0
"""An error that spans more than this over a whole run (µm) is beyond a machine tool's thermal drift: a column in
nm whose name gives no unit, read as µm, looks like this."""


def unit_note(name: str | None, label: str, values: np.ndarray | None = None) -> str | None:
    """The note of an error column read in another unit than µm (None for one in µm); with its ``values`` (µm),
    also of one whose name gives no unit and whose span over the run is too small or too large for µm
    (:data:`SMALLEST_ERROR_SPAN_UM`, :data:`LARGEST_ERROR_SPAN_UM`)."""
    unit, scale = length_unit(name)
    if factored_length_unit(name) is not None:
        return f"{label}: column '{name}' is in {unit} by its name: read ×{scale:g} as µm"
    signal = SIGNAL_UNIT.search(str(name)) if name is not None else None
    if scale == 1.0 and signal:
        return (
            f"{label}: column '{name}' is named in {signal.group(1) or signal.group(2)}, a transducer's signal, not "
            f"a length: read as µm; give its µm per volt or per count K as --error '{name}*K'"
        )
    scaled = scaled_name(name)
    if scaled is not None:
        return None if scale == 1.0 else f"{label}: column '{scaled[0]}' read ×{scale:g} as µm (--error '{name}')"
    if scale == 1.0 and values is not None and named_length_unit(name) is None:
        measured = values[np.isfinite(values)]
        span = float(np.ptp(measured)) if measured.size > 1 else None
        if span is not None and 0.0 < span < SMALLEST_ERROR_SPAN_UM:
            return (
                f"{label}: column '{name}' spans only {span:.3g} µm over the run, read as µm (its name gives no "
                f"unit): less than thermal drift and a displacement sensor show; if it is in mm, name it "
                f"'{name}_mm' (or '{name} [mm]') to read it ×1000"
            )
        if span is not None and span > LARGEST_ERROR_SPAN_UM:
            return (
                f"{label}: column '{name}' spans {span:.4g} µm over the run, read as µm (its name gives no unit): "
                f"more than a machine tool's thermal drift; if it is in nm, name it '{name}_nm' (or '{name} [nm]') "
                f"to read it ×0.001; in steps or counts, give their µm K as --error '{name}*K'"
            )
    if scale == 1.0:
        return None
    return f"{label}: column '{name}' is in {unit} by its name: read ×{scale:g} as µm (rename it to read it as µm)"


@dataclass(frozen=True)
class LoadOptions:
    """The column and value options of :func:`load_run` (its parameters say what each means)."""

    temps: Sequence[str] | None = None
    time: str = DEFAULT_TIME
    error: str | None = DEFAULT_ERROR
    require_error: bool = True
    allow_nonfinite: bool = False
    missing_error: bool = False
    ambient: str | None = None
    """A column that is never a default input (the ambient temperature, whatever its name)."""
    temp_range: tuple[float, float] | None = TEMP_RANGE_C
    error_limit: float | None = ERROR_LIMIT_UM
    drop_glitches: bool | None = None
    """Take the error's glitches (:mod:`groupfit.glitches`) as not measured, with a note; None (not said): only
    where readings are averaged (``--resample``, readings in bursts): a glitch is left out of its period's mean."""
    check_ranges: bool | None = None
    """Check ``temp_range`` and ``error_limit``; None: unless ``allow_nonfinite`` (a replay, whose run-time
    rule meets an implausible reading as a sensor fault)."""
    temps_as_faults: bool = False
    """A validation run, read as ``replay`` reads a next run: a temperature outside ``temp_range`` is kept, as
    one that is not a number is, a fault of the run-time rule, where it would be refused (``--resample``
    still takes it as missed); a temperature's glitch is named and kept as logged, not interpolated."""
    sparse: tuple[str, ...] = ()
    """Columns read on some rows only (probe readings): resampled as the error is, never made up nor trimmed."""

    @property
    def ranges_checked(self) -> bool:
        return not self.allow_nonfinite if self.check_ranges is None else self.check_ranges


MISSING_TIME = "name the time column with --time COLUMN"
MISSING_ERROR = "name the thermal error's column with --error COLUMN"


def numeric_column(
    frame: pd.DataFrame, column: str, label: str, *, allow_nonfinite: bool, missing: str = ""
) -> np.ndarray:
    """Return one column as float64, naming the first bad cell if there is one; a cell marking a reading not
    taken (:data:`NO_READING`) is empty. ``missing``: what to do when the column is absent and no column's
    name is a near miss of it (``name the time column with --time COLUMN``).

    Rows are reported 1-based, counting data rows (the header is not a row).
    """
    if column not in frame.columns:
        available = ", ".join(map(str, frame.columns))
        alike = [str(c) for c in frame.columns if str(c).strip().casefold() == str(column).strip().casefold()]
        hint = f" ('{alike[0]}' differs only in case or spaces: rename it '{column}')" if len(alike) == 1 else ""
        cut = [str(c) for c in frame.columns if "," in str(c) and str(c).startswith(f"{column},")]
        if cut and not hint:
            hint = f" (a name with a comma in it is quoted in a list: --temps '\"{cut[0]}\",…')"
        wrong = misread(str(column), frame.columns) if not hint else None
        if wrong:
            hint = f" (the names read wrongly: '{wrong[0]}' is '{column}' in {wrong[1]}: give --encoding {wrong[1]})"
        renamed = renamed_from(str(column), frame.columns) if not hint else None
        hint = f" ('{renamed}' may be it under another name: rename it '{column}')" if renamed else hint
        if missing and not hint:
            hint = f" ({missing})"
        raise InputError(f"{label}: column '{column}' not found{hint}; the columns are: {available}")
    raw = frame[column]
    values, text, marked, _ = _cells(raw)
    bad_text = values.isna() & raw.notna() & (text.str.lower() != "nan") & ~marked
    if bad_text.any():
        row = int(np.flatnonzero(bad_text.to_numpy())[0])
        raise InputError(
            f"{label}: row {row + 1}, column '{column}': {raw.iloc[row]!r} is not a number; fix or remove that row"
        )
    array = values.to_numpy(dtype=float)
    if not allow_nonfinite:
        nonfinite = ~np.isfinite(array)
        if nonfinite.all() and not marked.any():
            raise InputError(
                f"{label}: column '{column}' holds no reading in the whole run (a channel not "
                "connected?); leave it out of the inputs (--temps), or name the column that holds the readings"
            )
        if nonfinite.any():
            row = int(np.flatnonzero(nonfinite)[0])
            what = (
                f"{raw.iloc[row]!r} (no reading)"
                if marked.iloc[row]
                else "empty"
                if np.isnan(array[row])
                else array[row]
            )
            readings, rows = log_readings(frame), log_rows(frame)
            raise InputError(
                f"{label}: {resampled_row(row, rows)}, column '{column}' is {what} "
                f"({missing_count(nonfinite, readings)}); a model can only be fitted on finite values: "
                f"{missing_advice(nonfinite, column, readings, rows)}"
            )
    return array


class _Cells(NamedTuple):
    """A column's cells as numbers (NaN where there is none), as stripped text, where they mark a reading not
    taken (:data:`NO_READING`) and where they hold anything (not empty, not ``nan``)."""

    values: pd.Series
    text: pd.Series
    marked: pd.Series
    filled: pd.Series

    @property
    def words(self) -> pd.Series:
        """Filled cells that are neither a number nor a mark of a reading not taken."""
        return self.values.isna() & self.filled & ~self.marked


def _cells(raw: pd.Series) -> _Cells:
    values = pd.to_numeric(raw, errors="coerce")
    text = raw.astype(str).str.strip()
    filled = raw.notna() & (text != "") & (text.str.lower() != "nan")
    return _Cells(values, text, raw.notna() & text.str.fullmatch(NO_READING), filled)


def refuse_bad_cells(frame: pd.DataFrame, label: str, *, skip: Sequence[str] = ()) -> None:
    """Refuse the first cell of a column of numbers (nine in ten of its filled cells) that is neither a number,
    empty, nor a mark of a reading not taken: averaging (``--resample``) would take it for a missed reading."""
    for column in frame.columns:
        raw = frame[column]
        if column in skip or pd.api.types.is_numeric_dtype(raw):
            continue
        cells = _cells(raw)
        bad = cells.words
        if bad.any() and cells.values.notna().sum() >= 0.9 * cells.filled.sum():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise InputError(
                f"{label}: row {row + 1}, column '{column}': {raw.iloc[row]!r} is not a number; fix or remove that row"
            )


def markers_emptied(frame: pd.DataFrame) -> pd.DataFrame:
    """The table with every column of numbers and no-reading marks (:data:`NO_READING`: ``---``, ``OVL``, ``ERR``)
    as float64, its marks empty, so that whatever reads the run's table later reads them as readings not taken.

    Columns holding any other text (a date-time, a comment) are left as they are.
    """
    converted = {}
    for column in frame.columns:
        raw = frame[column]
        if pd.api.types.is_numeric_dtype(raw):
            continue
        cells = _cells(raw)
        if cells.values.notna().any() and not cells.words.any():
            converted[column] = cells.values.astype(float)
    return frame.assign(**converted) if converted else frame


TEMP_RANGE_OPTION = "--range-temp=LOW,HIGH (or [data] temp_range)"
ERROR_RANGE_OPTION = "--range-error MAX (or [data] error_limit)"


def outside_bounds(values: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
    """The rows (0-based) of the finite readings outside ``bounds``."""
    low, high = bounds
    values = np.asarray(values, dtype=float)
    return np.flatnonzero(np.isfinite(values) & ((values < low) | (values > high)))


def check_range(
    values: np.ndarray, column: str, label: str, bounds: tuple[float, float], unit: str, option: str
) -> None:
    """Refuse the first finite reading outside ``bounds`` (a physically impossible value), naming row and column;
    a reading that is not finite is the loader's to refuse or keep (a validation run keeps it as a fault)."""
    low, high = bounds
    outside = outside_bounds(values, bounds)
    if outside.size:
        row = int(outside[0])
        if option == ERROR_RANGE_OPTION:
            _refuse_positions(values, column, label, high)
        raise InputError(
            f"{label}: row {row + 1}, column '{column}': {values[row]:g} {unit} is outside the plausible range "
            f"{low:g}…{high:g} {unit} ({outside.size} such value(s)); repair the data, widen the range with {option}, "
            "or take such readings as missed with --resample SECONDS (up to 3 in a row of a sensor are interpolated)"
        )


def implausible_as_missed(frame: pd.DataFrame, label: str, options: LoadOptions) -> tuple[pd.DataFrame, str | None]:
    """The log with its physically impossible readings emptied (a broken sensor's -999, a logger's overflow),
    for ``--resample`` to take as missed readings; and a note counting them (None: there were none).

    The inputs (``--temps``, else the columns named like sensors) outside ``temp_range`` and errors beyond
    ``error_limit``; other columns (a speed, a setpoint) are left as they are.
    """
    if not options.ranges_checked:
        return frame, None
    temps = options.temps
    if temps is None:
        temps = default_temperature_columns(frame.columns, exclude=(options.time, options.error, options.ambient))
    bounds = {t: options.temp_range for t in temps if options.temp_range is not None}
    if options.error is not None and options.error_limit is not None and not is_from_start(options.error):
        limit = options.error_limit / abs(length_unit(options.error)[1])
        bounds[options.error] = (-limit, limit)
    counts = {}
    frame = frame.copy()
    for column, (low, high) in bounds.items():
        if column not in frame.columns:
            continue
        values = pd.to_numeric(frame[column], errors="coerce")
        outside = (values < low) | (values > high)
        if column == options.error and outside.any() and not (values.notna() & ~outside).any():
            _refuse_error_outside(values.to_numpy(dtype=float) * length_unit(column)[1], column, label, options)
        if outside.any():
            frame.loc[outside.to_numpy(), column] = np.nan
            counts[column] = int(outside.sum())
    if not counts:
        return frame, None
    listed = ", ".join(f"{count} in '{column}'" for column, count in counts.items())
    return frame, f"{label}: readings outside the plausible range taken as missed ({listed})"


POSITION_LIMIT_UM = 1e8
"""The largest position (µm, 100 m) a machine's axis logs; beyond it a reading is a marker (``3e38``), not one."""


def _refuse_positions(values: np.ndarray, column: str, label: str, limit: float) -> None:
    """Refuse an error column (µm) every reading of which is beyond ±``limit`` while they span a plausible drift,
    none a marker beyond :data:`POSITION_LIMIT_UM`: positions logged from the machine's zero. Nothing otherwise."""
    rows = np.flatnonzero(np.isfinite(values))
    finite, row = values[rows], int(rows[0]) if rows.size else 0
    if not finite.size or not np.all(np.abs(finite) > limit) or np.max(np.abs(finite)) > POSITION_LIMIT_UM:
        return
    spread = float(np.ptp(finite))
    if 0.0 < spread < limit:  # drift plausible, level not
        raise InputError(
            f"{label}: column '{column}': every reading is beyond the plausible ±{limit:g} µm (row {row + 1}: "
            f"{values[row]:g} µm), while they span only {spread:.4g} µm: a position logged from the machine's zero, "
            "not a thermal error; read each reading less the run's first (the drift since the start) with "
            f"--error '{column}-start', or widen the range with --range-error MAX"
        )


def _refuse_error_outside(values: np.ndarray, column: str, label: str, options: LoadOptions) -> None:
    """Refuse an error column none of whose readings (µm) is plausible: nothing would be left to take as missed."""
    limit = options.error_limit
    _refuse_positions(values, column, label, limit)
    row = int(np.flatnonzero(np.isfinite(values))[0])
    raise InputError(
        f"{label}: column '{column}': every reading is beyond the plausible ±{limit:g} µm (row {row + 1}: "
        f"{values[row]:g} µm); widen the range with --range-error MAX, or name the thermal error's column"
    )


def temperature_inputs(frame: pd.DataFrame, label: str, options: LoadOptions) -> tuple[list, np.ndarray, str | None]:
    """The input columns and their readings; constant or empty columns among the default inputs are left out,
    with a note.

    A constant column named with ``--temps`` is refused (a dead sensor); one found by its name (a setpoint
    logged as ``T0_target``, a sensor that never moved) is not an input the user asked for. A run read
    without its error (a replay) keeps every column: the run-time rule meets a stuck sensor as the
    controller does.
    """
    temps, time, error, ambient = options.temps, options.time, options.error, options.ambient
    defaulted = temps is None
    notes = []
    if defaulted:
        temps = default_temperature_columns(frame.columns, exclude=(time, error, ambient))
        if not temps and options.require_error:
            temps = temperature_like_columns(frame, exclude=(time, error, ambient))
            if temps:
                references = ambient_columns(frame, temps)  # the air a reference is taken from is not left out
                air = temperature_like_columns(frame, (time, error, ambient), air=True)
                air = [c for c in air if c not in references]
                every = ",".join(str(c) for c in frame.columns if c in temps or c in air)
                named = (
                    f"; {', '.join(air)} {'is' if len(air) == 1 else 'are'} named as the air and not an input: "
                    f"--temps {every} takes {'it' if len(air) == 1 else 'them'} too"
                    if air
                    else "; --temps names them"
                )
                notes.append(
                    f"{label}: no column is named as a temperature (T1, Temp …, °C): the inputs are the columns "
                    f"whose readings look like temperatures in °C: {', '.join(temps)}{named}"
                )
        if not temps:
            raise InputError(
                f"{label}: no temperature columns found (named T1, T2 … or in °C); name the inputs with --temps A,B,C. "
                f"The columns are: {', '.join(map(str, frame.columns))}"
            )
    temps = list(temps)
    duplicates = sorted({t for t in temps if temps.count(t) > 1})
    if duplicates:
        raise InputError(f"{label}: temperature column(s) listed twice: {', '.join(duplicates)}")
    if error is not None and error in temps:
        raise InputError(f"{label}: column '{error}' is both the error and a temperature input")

    empty = [t for t in temps if defaulted and _without_readings(frame, t)] if options.require_error else []
    temps = [t for t in temps if t not in empty] if len(empty) < len(temps) else temps
    columns = [numeric_column(frame, t, label, allow_nonfinite=options.allow_nonfinite) for t in temps]
    constant = {}
    for t, column in zip(temps, columns):
        finite = column[np.isfinite(column)]
        if options.require_error and finite.size and np.ptp(finite) == 0.0:  # a replay runs what it reads
            constant[t] = finite[0]
    if constant and (not defaulted or len(constant) == len(temps)):
        t, value = next(iter(constant.items()))
        raise InputError(
            f"{label}: temperature column '{t}' is constant ({value:g} °C) over the whole run; "
            "a fit cannot use it (a dead sensor?): repair it, or leave it out of the model's inputs "
            "(groupfit fit --temps)"
        )
    kept = [j for j, t in enumerate(temps) if t not in constant]
    array = np.column_stack([columns[j] for j in kept]) if kept else np.empty((len(frame), 0))
    twins = twin_note(label, [temps[j] for j in kept], array) if options.require_error else None
    notes += [twins] if twins else []
    if constant:
        listed = ", ".join(f"'{t}' ({v:g} °C)" for t, v in constant.items())
        notes.append(
            f"{label}: constant over the whole run, left out of the inputs: {listed} (a setpoint or a sensor that "
            "never moved); --temps names the inputs"
        )
    if empty:
        listed = ", ".join(f"'{t}'" for t in empty)
        notes.append(
            f"{label}: no reading in the whole run, left out of the inputs: {listed} (a channel not connected); "
            "--temps names the inputs"
        )
    return [temps[j] for j in kept], array, "; ".join(notes) or None


def _without_readings(frame: pd.DataFrame, column: str) -> bool:
    """Whether a column holds no finite number at all, every cell empty or marking a reading not taken (a
    logger's channel with nothing connected); one holding other text is refused by the reading, naming it."""
    cells = _cells(frame[column])
    return not np.isfinite(cells.values.to_numpy(dtype=float)).any() and not cells.words.any()


FAR_FIRST_SHARE = 0.9
"""An error read from its first reading (``COLUMN-start``) with this share of its readings beyond the plausible
range from it was taken from a marker or a glitch."""


def _from_first_reading(values: np.ndarray, error: str, label: str, limit: float | None) -> np.ndarray:
    """``values`` less their first reading; refused when most of them lie beyond ``limit`` from it."""
    zeroed = from_start(values)
    finite = np.flatnonzero(np.isfinite(zeroed))
    if limit is not None and finite.size > 1 and np.mean(np.abs(zeroed[finite]) > limit) >= FAR_FIRST_SHARE:
        row = int(finite[0])
        raise InputError(
            f"{label}: column '{error}': the error is read from its first reading (row {row + 1}: {values[row]:g} "
            f"µm as logged), and most of the others lie more than {limit:g} µm from it: that reading is a marker "
            "or a glitch; repair or drop that row"
        )
    return zeroed


def error_values(frame: pd.DataFrame, error: str | None, label: str, options: LoadOptions) -> np.ndarray | None:
    """The error column as numbers (None when not asked for and absent), refused when it cannot be modelled."""
    require_error, missing_error = options.require_error, options.missing_error
    allow_nonfinite = options.allow_nonfinite
    if error is None or not (require_error or error in frame.columns):
        return None
    error_values = numeric_column(
        frame, error, label, allow_nonfinite=allow_nonfinite or missing_error, missing=MISSING_ERROR
    )
    if missing_error and not allow_nonfinite:
        infinite = np.flatnonzero(np.isinf(error_values))
        if infinite.size:
            raise InputError(
                f"{label}: row {int(infinite[0]) + 1}, column '{error}' is {error_values[infinite[0]]} "
                "(an empty cell marks a row without a measurement); repair or drop that row"
            )
        if np.isnan(error_values).all():
            raise InputError(f"{label}: error column '{error}' is empty on every row; a model needs it")
    error_values = error_values * length_unit(error)[1]
    if is_from_start(error):
        error_values = _from_first_reading(error_values, error, label, options.error_limit)
    measured = error_values[np.isfinite(error_values)]
    if require_error and measured.size > 1 and np.ptp(measured) == 0.0:
        raise InputError(
            f"{label}: error column '{error}' is constant ({measured[0]:g} µm) on every measured row; "
            "there is nothing to model: name the thermal-error column with --error COLUMN"
        )
    return error_values


__all__ = [
    "ERROR_LIMIT_UM",
    "NO_READING",
    "markers_emptied",
    "refuse_bad_cells",
    "LARGEST_ERROR_SPAN_UM",
    "SMALLEST_ERROR_SPAN_UM",
    "TEMP_RANGE_C",
    "LoadOptions",
    "check_range",
    "outside_bounds",
    "error_values",
    "implausible_as_missed",
    "numeric_column",
    "temperature_inputs",
    "unit_note",
]
