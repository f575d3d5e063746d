"""A time column of spreadsheet serial dates or MATLAB datenums, read as the local date-times they stand for.

A spreadsheet keeps a date-time cell as the days since 1899-12-30 (``46320.5`` is 2026-10-25 12:00), and a
CSV or a workbook saved from it may hold those numbers; MATLAB's datenum counts from the year 0. Such a number
names no time zone: like a text stamp without a UTC offset (``2026-10-25 02:30:00``) it is the wall-clock time
of the logger's place. The column is read as text date-times are: in seconds since its first row, the first
row's date-time kept as the run's clock origin, and a local clock's change to or from summer time read through
with a note (:mod:`groupfit.clock_changes`), so that a log of serial dates reads as the same log stamped in
text.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from groupfit.clock_changes import CLOCK_SHIFTS, through_clock_changes
from groupfit.elapsed_times import DAY_S
from groupfit.readtable import CLOCK_NOTES, CLOCK_ORIGIN
from groupfit.timestamps import SHORTEST_RUN_S, SLOWEST_PERIOD_S, STAMP_RESOLUTIONS_S, numbers_without_unit

SERIAL_DAYS = (20000.0, 80000.0)
"""Spreadsheet serial dates (days since 1899-12-30) of 1954 … 2119: a date column exported as numbers."""
DATENUM_OFFSET = 693960.0
"""MATLAB's datenum (days since the year 0) less a spreadsheet's serial date of the same day."""
SERIAL_KINDS = (
    (0.0, "spreadsheet serial dates (days since 1899-12-30)"),
    (DATENUM_OFFSET, "MATLAB datenums (days since the year 0)"),
)
UNIX_EPOCH_SERIAL = 25569.0
"""The spreadsheet serial date of 1970-01-01."""
FINEST_PRECISION_S = 1e-4
"""How closely a serial date's number places its date-time beyond the decimals it was written to (a double's
rounding of days since 1899 or the year 0 is some 10 µs)."""
DATE_WORD = re.compile(r"date|datum", re.IGNORECASE)


def serial_days_to_seconds(frame: pd.DataFrame, column: str, label: str) -> str | None:
    """A date column of spreadsheet serial dates or MATLAB datenums converted in place to seconds since its
    first row, and its note (None: not one).

    A time column without a unit whose numbers all lie among the serial dates of 1954 … 2119 (or the
    datenums of those years), less than a day apart, is a date-time written as a number when its name says
    it is a date (``Date``, ``Datum/Zeit``), or when only the reading in days makes a thermal run of it:
    read in seconds it lasts less than :data:`~groupfit.timestamps.SHORTEST_RUN_S`, read in days it lasts
    longer, sampled at least every :data:`~groupfit.timestamps.SLOWEST_PERIOD_S` (``Timestamp`` 46082.333,
    46082.334 …; ``time`` 740042.333 …).

    The first row's date-time is kept as ``frame.attrs[CLOCK_ORIGIN]`` (seconds since 1970, read as UTC, in
    the clock of the last row), and a local clock's changes to and from summer time are read through as they
    are in text stamps, with their note in ``frame.attrs[CLOCK_NOTES]`` and the rows they moved in
    ``frame.attrs[CLOCK_SHIFTS]`` (:func:`groupfit.readtable.datetimes_to_seconds`).
    """
    days = numbers_without_unit(frame, column)
    if days is None or len(days) < 2:
        return None
    offset, kind = next(
        ((offset, what) for offset, what in SERIAL_KINDS if SERIAL_DAYS[0] <= days.min() - offset <= SERIAL_DAYS[1]),
        (None, None),
    )
    if kind is None or days.max() - days.min() > SERIAL_DAYS[1] - SERIAL_DAYS[0]:
        return None
    step = float(np.median(np.diff(days)))
    if not 0.0 < step < 1.0:
        return None
    span = float(days[-1] - days[0])
    a_run_in_days = span < SHORTEST_RUN_S <= span * DAY_S and step * DAY_S <= SLOWEST_PERIOD_S
    if not (DATE_WORD.search(str(column)) or a_run_in_days):
        return None
    wall_s = _wall_clock_seconds(days, offset)
    seconds, origin = wall_s - wall_s[0], float(wall_s[0])
    stamps = pd.Series(pd.to_datetime(wall_s, unit="s"))  # naive date-times: local, naming no zone
    seconds, origin, clock_note, frame.attrs[CLOCK_SHIFTS] = through_clock_changes(
        stamps, seconds, origin, label, column
    )
    frame[column] = seconds
    frame.attrs[CLOCK_ORIGIN] = float(origin)
    frame.attrs[CLOCK_NOTES] = (clock_note,) if clock_note else ()
    return f"{label}: column '{column}' holds {kind}: read in seconds"


def _wall_clock_seconds(days: np.ndarray, offset: float) -> np.ndarray:
    """Serial dates (``offset``: of :data:`SERIAL_KINDS`) as wall-clock date-times in seconds since 1970, read as
    UTC, set on the coarsest of :data:`~groupfit.timestamps.STAMP_RESOLUTIONS_S` that every one lies within its
    number's precision of, among those more than twice that precision (as written where none is): a log stamped
    in whole seconds reads as whole seconds, as its text would, from days written to six decimals (0.04 s), and
    one stamped in whole minutes as whole minutes from four (4 s), so that the stamp of the hour a clock goes
    back to (02:00:00) is not read a moment before it."""
    wall_s = (days - offset - UNIX_EPOCH_SERIAL) * DAY_S
    precision_s = 0.5 * _written_step_days(days) * DAY_S + FINEST_PRECISION_S
    for resolution in STAMP_RESOLUTIONS_S:
        if precision_s >= resolution / 2:  # any number lies that close to a stamp of this resolution
            break
        counts = np.round(wall_s / resolution)
        if np.all(np.abs(wall_s - counts * resolution) <= precision_s):
            return counts * resolution
    return wall_s


def _written_step_days(days: np.ndarray) -> float:
    """The step of the last decimal the serial dates were written to (1e-6 for ``46320.083333``); 0 where they
    were not cut to fewer than ten decimals (a workbook's date-time cell)."""
    for decimals in range(10):
        scaled = days * 10.0**decimals
        if np.all(np.abs(scaled - np.round(scaled)) <= 0.01):
            return 10.0**-decimals
    return 0.0


__all__ = ["DATENUM_OFFSET", "SERIAL_DAYS", "SERIAL_KINDS", "serial_days_to_seconds"]
