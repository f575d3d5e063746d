"""Load and validate a run: a time column, temperature columns and the thermal error.

A *run* is one recording of a machine (or one simulation) sampled at a uniform period. :func:`load_run` reads
it from a CSV file or a pandas DataFrame, checks it once and converts the model's columns into numpy arrays. Every
problem a user can cause is an :class:`~groupfit.errors.InputError` naming the file, the column and the row.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.clock_changes import CLOCK_SHIFTS, shift_at
from groupfit.column_values import ERROR_LIMIT_UM as ERROR_LIMIT_UM
from groupfit.column_values import (
    ERROR_RANGE_OPTION,
    MISSING_TIME,
    TEMP_RANGE_OPTION,
    implausible_as_missed,
    markers_emptied,
    refuse_bad_cells,
    temperature_inputs,
)
from groupfit.column_values import TEMP_RANGE_C as TEMP_RANGE_C
from groupfit.column_values import LoadOptions as LoadOptions
from groupfit.column_values import check_range as check_range
from groupfit.column_values import error_values as read_error_values
from groupfit.column_values import numeric_column as numeric_column
from groupfit.columns import aligned_inputs
from groupfit.default_columns import DEFAULT_ERROR, DEFAULT_TIME, found_error_column
from groupfit.default_columns import length_unit as length_unit
from groupfit.error_level import error_unit_note
from groupfit.error_scale import with_scaled_error
from groupfit.errors import InputError
from groupfit.glitches import temperatures_without_glitches, without_glitches
from groupfit.interleaved import refuse_interleaved, stamp_groups
from groupfit.readtable import (
    CLOCK_NOTES,
    CLOCK_ORIGIN,
    LEFT_OUT_TAIL,
    datetimes_to_seconds,
    read_table,
    without_stray_rows,
)
from groupfit.record_kinds import record_kinds_cycle
from groupfit.resample import jitter_note, resample_frame
from groupfit.run import Run as Run
from groupfit.sampling import clock_of, described_burst_cycle
from groupfit.serial_dates import serial_days_to_seconds
from groupfit.split_stamps import with_milliseconds
from groupfit.stamp_channel_row import found_time_without_channel_row
from groupfit.stuck_sensors import stuck_sensor_notes
from groupfit.timestamps import (
    epoch_to_seconds,
    names_a_unit,
    unit_notes,
    unit_seconds,
)
from groupfit.units_row import read_in_row_units

PERIOD_TOLERANCE = 0.02
"""Largest relative deviation of one sampling interval from the run's period (``--period-tolerance``)."""


MAX_TIME_S = 1e11
"""Largest plausible time stamp in seconds (some 3000 years): a larger one is a corrupt cell."""


def time_seconds(frame: pd.DataFrame, column: str, label: str) -> np.ndarray:
    """The time column in seconds (date-times from the first row; numbers in the unit the column's name ends
    in, :func:`groupfit.timestamps.unit_seconds`), in place; a bad or implausible cell named with its row."""
    numbers = column in frame.columns and pd.api.types.is_numeric_dtype(frame[column])
    datetimes_to_seconds(frame, column, label)
    values = numeric_column(frame, column, label, allow_nonfinite=True, missing=MISSING_TIME)
    unstamped = np.flatnonzero(np.isnan(values))
    if unstamped.size:
        cell = str(frame[column].iloc[unstamped[0]]).strip()
        what = "is empty" if cell.lower() in ("", "nan", "<na>", "none") else f"holds {cell!r}, not a time"
        raise InputError(
            f"{label}: row {unstamped[0] + 1}, column '{column}' {what} ({unstamped.size} row(s) without a time "
            "stamp): a reading cannot be placed without its time; fill in the time or delete the row"
        )
    if not np.isfinite(values).all():
        numeric_column(frame, column, label, allow_nonfinite=False)  # names the infinite cell
    scale = unit_seconds(column, label) if numbers else 1.0
    if scale != 1.0:
        values = values * scale
        frame[column] = values
    refuse_beyond(values, MAX_TIME_S, column, label, "s is not a plausible time")
    return values


def refuse_beyond(values: np.ndarray, limit: float, column: str, label: str, what: str) -> None:
    """One line naming the first cell whose magnitude exceeds ``limit`` (``what``: its unit and what it is not)."""
    huge = np.flatnonzero(np.abs(values) > limit)
    if huge.size:
        raise InputError(
            f"{label}: row {huge[0] + 1}, column '{column}': {values[huge[0]]:g} {what} (beyond {limit:g}); "
            "repair that cell"
        )


def load_run(
    source: str | Path | pd.DataFrame,
    *,
    temps: Sequence[str] | None = None,
    time: str = DEFAULT_TIME,
    error: str | None = DEFAULT_ERROR,
    require_error: bool = True,
    allow_nonfinite: bool = False,
    missing_error: bool = False,
    name: str | None = None,
    temp_range: tuple[float, float] | None = TEMP_RANGE_C,
    error_limit: float | None = ERROR_LIMIT_UM,
    period_tolerance: float = PERIOD_TOLERANCE,
    resample: float | None = None,
    time_is_default: bool = False,
    error_is_default: bool = False,
    drop_glitches: bool | None = None,
    check_ranges: bool | None = None,
    encoding: str | None = None,
    sparse: tuple[str, ...] = (),
    temps_as_faults: bool = False,
) -> Run:
    """Read and validate a run.

    Parameters
    ----------
    source : path or DataFrame
        A CSV file with a header line, one row per sample, or a DataFrame.
    temps : sequence of str, optional
        Temperature columns used as model inputs, in order. Default: the
        columns named like sensors, ``T`` followed by a digit (``T1``,
        ``T2_front`` …); an ambient column such as ``T_amb`` is not included.
        An empty sequence loads a run without temperature inputs (e.g. a
        heat-flux run for the AR(1) model).
    time, error : str
        Names of the time (s) and thermal-error (µm) columns.
    require_error : bool
        When False, a run without the error column is accepted (``error`` is None).
    allow_nonfinite : bool
        When True, NaN and ±inf in temperature and error columns are kept
        (the run-time switching logic treats them as sensor faults).
    missing_error : bool
        When True, empty error cells are kept as NaN: rows where the error
        was not measured (a probe cycle every few minutes while the
        temperatures are logged throughout). At least one row must have it.
    name : str, optional
        Name of the run (default: the file stem).
    temp_range : (low, high) or None
        Plausible temperature readings in °C (default :data:`TEMP_RANGE_C`);
        a reading outside is refused with its row and column. None: no check.
    error_limit : float or None
        Largest plausible ``|error|`` in µm (default :data:`ERROR_LIMIT_UM`).
        With ``allow_nonfinite`` neither range is checked: the run-time rule
        treats implausible readings as sensor faults, as it does NaN.
    period_tolerance : float
        Largest relative deviation of an interval from the period (default
        :data:`PERIOD_TOLERANCE`); a jittering clock within it is accepted
        with a note giving its largest deviation.
    resample : float, optional
        Bin the rows into periods of this many seconds first
        (:mod:`groupfit.resample`); a gap that splits the log is refused here
        (:func:`load_runs` returns the pieces).
    time_is_default : bool
        ``time`` is a default, not asked for (the column a model was fitted
        with): a log without it is read on the column its name marks as the
        time, with a note, as a log without ``time_s`` is.
    error_is_default : bool
        The same for ``error`` (a replay of a model on a log that names its
        error otherwise): the one column named as an error is read, with a note.
    drop_glitches : bool, optional
        Take the error's glitches (:mod:`groupfit.glitches`: readings that
        leave their neighbours and come back) as not measured, with a note
        naming their rows; for a run that may hold unmeasured rows
        (``missing_error`` or ``allow_nonfinite``). None (not said): only where
        readings are averaged (``resample``, readings in bursts), a glitch
        left out of its period's mean.
    check_ranges : bool, optional
        Refuse readings outside ``temp_range`` and ``error_limit`` (with
        ``resample``: take them as missed) even with ``allow_nonfinite``, for a
        run whose residual is fitted rather than replayed (``diagnose``).
        Default: unless ``allow_nonfinite``.
    encoding : str, optional
        The text's encoding (``--encoding``); by default it is told from the bytes (:mod:`groupfit.textencoding`).
    sparse : tuple of str
        Columns read on some rows only (a probe's readings): ``resample`` fills no period of theirs.
    temps_as_faults : bool
        A validation run, read as ``replay`` reads a next run: a temperature outside ``temp_range`` is kept, a
        fault of the run-time rule, as one that is not a number is; a temperature's glitch is named in a note
        and kept as logged (with ``drop_glitches``), not interpolated.

    Raises
    ------
    InputError
        On any problem with the file or its values.
    """
    options = dict(temps=temps, time=time, error=error, require_error=require_error, allow_nonfinite=allow_nonfinite)
    options.update(missing_error=missing_error, temp_range=temp_range, error_limit=error_limit)
    options.update(drop_glitches=drop_glitches, check_ranges=check_ranges, encoding=encoding, sparse=tuple(sparse))
    options.update(temps_as_faults=temps_as_faults)
    defaults = dict(time_is_default=time_is_default, error_is_default=error_is_default)
    runs = load_runs(source, name=name, period_tolerance=period_tolerance, resample=resample, **defaults, **options)
    if len(runs) > 1:
        raise InputError(
            f"{runs[0].source.split(' (part')[0]}: {f'--resample {resample:g}' if resample else 'the clock'} splits "
            f"the log into {len(runs)} runs at "
            "gaps; this takes one run: cut the file at the gap, or give the parts as separate runs"
        )
    return runs[0]


def load_runs(
    source: str | Path | pd.DataFrame,
    *,
    name: str | None = None,
    period_tolerance: float = PERIOD_TOLERANCE,
    resample: float | None = None,
    time_is_default: bool = False,
    error_is_default: bool = False,
    **options,
) -> list[Run]:
    """Read and validate a log as :func:`load_run` does; with ``resample``, one run per stretch between gaps.

    A log without the default time or error column (``time_s``, ``error_um``) is read on the one its name
    marks for the role (:mod:`groupfit.default_columns`), with a note.
    """
    frame, run_name, label = read_table(source, name, options.pop("encoding", None))
    frame, stray_notes, left_out = without_stray_rows(frame, label)
    asked_time = options.get("time", DEFAULT_TIME)
    frame, time, time_note, channel_note = found_time_without_channel_row(
        frame, asked_time, label, default=time_is_default
    )
    if channel_note:
        left_out = "; ".join(filter(None, (left_out, channel_note[len(label) + 2 : channel_note.index(LEFT_OUT_TAIL)])))
    lengths, units_notes = read_in_row_units(frame, time, label)
    serial_note = serial_days_to_seconds(frame, time, label) or epoch_to_seconds(frame, time, label)
    millis_note = with_milliseconds(frame, time, label)
    required = options.get("require_error", True)
    asked = options.get("error", DEFAULT_ERROR)
    frame = with_scaled_error(frame, asked, label, lengths=lengths, required=required and not error_is_default)
    error, error_note = found_error_column(
        frame, asked, label, required=required, default=error_is_default, lengths=lengths, time=time
    )
    try:
        runs = _read_runs(frame, run_name, label, period_tolerance, resample, {**options, "time": time, "error": error})
    except InputError as exc:
        if left_out and " row " in str(exc):
            raise InputError(f"{exc} (rows are counted without those left out: {left_out})") from None
        raise
    notes = (*stray_notes, time_note, channel_note, *units_notes, serial_note, millis_note, error_note)
    found = tuple(note for note in notes if note)
    return [dataclasses.replace(run, notes=(*found, *run.notes)) for run in runs] if found else runs


def _read_runs(frame, run_name, label, period_tolerance, resample, options) -> list[Run]:
    time = options.get("time", DEFAULT_TIME)
    bursts = None
    if resample is None:
        try:
            return [_validated(frame.copy(), run_name, label, period_tolerance=period_tolerance, notes=(), **options)]
        except InputError:
            bursts = _bursts(frame, time, label)
            if bursts is None:
                raise
        resample = bursts[1]
    else:
        time_seconds(frame, time, label)
    error = options.get("error", DEFAULT_ERROR)
    clock = dict(clock_origin=frame.attrs.get(CLOCK_ORIGIN), clock_shifts=frame.attrs.get(CLOCK_SHIFTS))
    refuse_bad_cells(frame, label, skip=(time,))
    frame, missed = implausible_as_missed(frame, label, LoadOptions(**options))
    frame, glitched = _glitches_as_missed(frame, label, LoadOptions(**options))
    measured = (*((error,) if error else ()), *options.get("sparse", ()))
    binned = resample_frame(frame, time=time, period_s=float(resample), label=label, measured=measured)
    note = binned.note(label, float(resample), sum(len(piece) for piece in binned.pieces))
    if bursts is not None:
        note = f"{label}: {bursts[0]} (as --resample {bursts[1]:g} does); " + note.removeprefix(f"{label}: ")
    notes = tuple(n for n in (missed, glitched) if n) + (note, *frame.attrs.get(CLOCK_NOTES, ()))
    if len(binned.pieces) == 1:
        return [
            _validated(
                binned.pieces[0],
                run_name,
                label,
                period_tolerance=period_tolerance,
                notes=notes,
                **clock,
                **options,
            )
        ]
    total = len(binned.pieces)
    return [
        _validated(
            piece,
            f"{run_name}#{k}",
            f"{label} (part {k} of {total})",
            period_tolerance=period_tolerance,
            notes=notes if k == 1 else (),
            **clock,
            **options,
        )
        for k, piece in enumerate(binned.pieces, start=1)
    ]


def _bursts(frame: pd.DataFrame, time: str, label: str) -> tuple[str, float] | None:
    """What the note says and the period of a log read in bursts (:func:`~groupfit.sampling.burst_cycle`) or of
    records of several kinds (:mod:`groupfit.record_kinds`), its time column read in seconds in place; None
    when it is neither (or its time cannot be read)."""
    try:
        seconds = time_seconds(frame, time, label)
    except InputError:
        return None
    return described_burst_cycle(seconds) or record_kinds_cycle(frame, time, seconds)


def _glitches_as_missed(frame: pd.DataFrame, label: str, options: LoadOptions) -> tuple[pd.DataFrame, str | None]:
    """The log with its error's glitches emptied before ``--resample`` averages them in, and a note."""
    error = options.error
    if options.drop_glitches is False or error is None or error not in frame.columns:
        return frame, None
    values = pd.to_numeric(frame[error], errors="coerce").to_numpy(dtype=float) * length_unit(error)[1]
    _, glitches, note = without_glitches(values, error, label)
    if note is None:
        return frame, None
    frame = frame.copy()
    frame.loc[frame.index[glitches], error] = np.nan
    return frame, note


def _validated(
    frame: pd.DataFrame,
    run_name: str,
    label: str,
    *,
    period_tolerance: float = PERIOD_TOLERANCE,
    notes: tuple[str, ...] = (),
    clock_origin: float | None = None,
    clock_shifts: tuple[tuple[float, float], ...] | None = None,
    **given,
) -> Run:
    """The checks of :func:`load_run` on a table already read (its keywords in ``given``); ``ambient`` (a
    column) is never a default input. ``clock_*``: the log's :data:`~groupfit.readtable.CLOCK_ORIGIN` and
    :data:`~groupfit.clock_changes.CLOCK_SHIFTS` where ``frame`` is a part of it built anew (``--resample``)."""
    options = LoadOptions(**given)
    time, error = options.time, options.error
    temp_range, error_limit = options.temp_range, options.error_limit
    counted = time in frame.columns and pd.api.types.is_numeric_dtype(frame[time]) and not names_a_unit(time)
    time_values = time_seconds(frame, time, label)
    clock_origin = frame.attrs.get(CLOCK_ORIGIN, clock_origin)
    clock_shifts = frame.attrs.get(CLOCK_SHIFTS, clock_shifts)
    if np.any(np.diff(time_values) <= 0):  # before check_time advises averaging the readings of each period
        refuse_interleaved(frame, [stamp_groups(time_values)], time=time, label=label)
    time_values, period, spread = clock_of(time_values, label, time, tolerance=period_tolerance)
    jitter = jitter_note(label, time_values, period)
    notes = tuple(notes) + ((jitter,) if jitter and not notes else ()) + ((spread,) if spread else ())
    notes = notes + unit_notes(label, time, time_values, period, unit_named=not counted)
    notes = notes + frame.attrs.get(CLOCK_NOTES, ())

    temps, temp_array, dropped = temperature_inputs(frame, label, options)
    notes = notes + ((dropped,) if dropped else ())

    error_values = read_error_values(frame, error, label, options)
    in_other_unit = error_unit_note(error, label, error_values, temp_array) if error_values is not None else None
    notes = notes + ((in_other_unit,) if in_other_unit else ())
    if options.ranges_checked:
        if temp_range is not None and not options.temps_as_faults:
            for j, t in enumerate(temps):
                check_range(temp_array[:, j], t, label, temp_range, "°C", TEMP_RANGE_OPTION)
        if error_limit is not None and error_values is not None:
            check_range(error_values, error, label, (-error_limit, error_limit), "µm", ERROR_RANGE_OPTION)
    if options.drop_glitches:  # after the ranges: an implausible reading is refused or a fault, never interpolated
        plausible = temp_range if options.temps_as_faults else None
        frame, temp_array, glitched = temperatures_without_glitches(  # a validation run's are named, kept as logged
            frame, temps, temp_array, label, options.ambient, plausible, as_logged=options.temps_as_faults
        )
        notes = notes + ((glitched,) if glitched else ())
    if options.drop_glitches and error_values is not None:
        error_values, _, glitched = without_glitches(error_values, error, label)
        notes = notes + ((glitched,) if glitched else ())
    notes = notes + stuck_sensor_notes(temp_array, temps, time_values, label)

    return Run(
        name=run_name,
        source=label,
        time=time_values,
        temps=temp_array,
        temp_names=tuple(temps),
        error=error_values,
        error_name=error if error_values is not None else None,
        period=period,
        frame=markers_emptied(frame),
        time_name=time,
        notes=notes,
        clock_origin_s=clock_origin,
        clock_shift_s=None if clock_origin is None else shift_at(clock_shifts, float(time_values[0])),
    )


def without_implausible_errors(run: Run, limit: float = ERROR_LIMIT_UM) -> Run:
    """The run with readings of its error beyond ``limit`` µm (a logger's overflow, 3e38) taken as not measured,
    and a note naming them: a replay scores what was measured, never an overflow."""
    if run.error is None:
        return run
    beyond = np.flatnonzero(np.abs(run.error) > limit)
    if not beyond.size:
        return run
    rows = ", ".join(str(i + 1) for i in beyond[:5]) + (" …" if beyond.size > 5 else "")
    note = (
        f"{run.source}: {beyond.size} reading(s) of the error beyond ±{limit:g} µm (row {rows}, "
        f"{run.error[beyond[0]]:g} µm first): not a thermal error, left out of the score as not measured"
    )
    error = run.error.copy()
    error[beyond] = np.nan
    return dataclasses.replace(run, error=error, notes=(*run.notes, note))


def loading_notes(runs: Sequence[Run]) -> list[str]:
    """What loading did to the runs (a jittering clock, a resampling, glitches left out), each note once."""
    return list(dict.fromkeys(note for run in runs for note in run.notes))


def measured_rows(run: Run) -> Run:
    """The run restricted to the rows with a measured error (the run itself when every row has one), at least two."""
    rows = np.isfinite(run.error)
    if rows.sum() < 2:
        raise InputError(f"{run.source}: {int(rows.sum())} row(s) with a measured error; a model needs two or more")
    if rows.all():
        return run
    frame = run.frame.loc[rows].reset_index(drop=True)
    return dataclasses.replace(run, time=run.time[rows], temps=run.temps[rows], error=run.error[rows], frame=frame)


def join_runs(runs: Sequence[Run]) -> Run:
    """Several runs of one machine laid end to end, as one run for a global model.

    The runs must share the sampling period (within the tolerance) and the
    input columns; time is renumbered to continue from run to run, so that a
    global model (p = 0) can be fitted on all of them. ``Run.frame`` keeps every
    column the runs share. A grouped model's breaks belong to one run: it is
    not fitted on joined runs.
    """
    runs = list(runs)
    if len(runs) == 1:
        return runs[0]
    runs = aligned_inputs(runs)
    first = runs[0]
    for run in runs[1:]:
        if abs(run.period - first.period) > 0.01 * first.period:
            raise InputError(
                f"{run.source}: sampled every {run.period:g} s but {first.source} every {first.period:g} s; "
                "resample the runs to one period"
            )
    if any(run.error is None for run in runs):
        missing = next(run for run in runs if run.error is None)
        raise InputError(f"{missing.source}: no error column; every joined run needs one")
    n = sum(run.n_samples for run in runs)
    shared = [c for c in first.frame.columns if all(c in run.frame.columns for run in runs)]
    return Run(
        name="+".join(run.name for run in runs),
        source=", ".join(run.source for run in runs),
        time=first.time[0] + first.period * np.arange(n),
        temps=np.vstack([run.temps for run in runs]),
        temp_names=first.temp_names,
        error=np.concatenate([run.error for run in runs]),
        error_name=first.error_name,
        period=first.period,
        frame=pd.concat([run.frame[shared] for run in runs], ignore_index=True),
        time_name=first.time_name,
        reference=_shared_reference(runs),
        notes=tuple(note for run in runs for note in run.notes),
    )


def _shared_reference(runs: Sequence[Run]) -> str | None:
    """The reference every joined run's inputs are relative to (they must agree)."""
    references = {run.reference for run in runs}
    if len(references) > 1:
        raise InputError("the runs' inputs are relative to different references; load them alike")
    return references.pop()
