"""A time stamp written over two columns: the date in one, the time of day in the next, read as one stamp.

Many loggers write the date and the time of day apart: a German CSV's
``Datum;Zeit`` (``24.10.2026;20:00:00``), a HOBO, Graphtec or Excel export's
``Date,Time`` (``10/24/2026,8:00:00 PM``), ``date,time`` in ISO 8601
(``2026-10-24,20:00:00``), a workbook's date cell beside a time cell. When
the time column (found by its name or named with ``--time``) holds dates
alone and the column after it times of day, or it holds times of day and the
column before it dates, the two are joined into one column named by both
(``Datum Zeit``), holding ``24.10.2026 20:00:00``, and read as a log with one
such column is: day and month told apart, AM and PM, a local clock's change
to or from summer time (:mod:`groupfit.clock_changes`). The time-of-day
column is then no column of its own (no input, no condition).

A date column beside anything else (daily data) and a time of day without a
date column keep their reading.
"""

from __future__ import annotations

import datetime
from typing import NamedTuple

import numpy as np
import pandas as pd

from groupfit.default_columns import found_time_column
from groupfit.errors import InputError
from groupfit.timestamps import DATE_FORMATS, TIME_FORMATS, named_time_unit, parses, time_like_columns

MIDNIGHT_STEP_S = 2 * 3600.0
"""A time of day that goes back by more than this on one date passed midnight (a change to or from summer time
goes back an hour)."""


class Stamp(NamedTuple):
    """A date column and the time-of-day column after it, and their cells as text (empty cells missing)."""

    date: str
    clock: str
    dates: pd.Series
    times: pd.Series
    fractions: bool
    """The times of day are numbers, fractions of a day."""


def found_stamp_column(frame: pd.DataFrame, time: str, label: str, *, default: bool = False) -> tuple[str, str | None]:
    """The time column to read, as :func:`~groupfit.default_columns.found_time_column` finds it, with a date
    column and a time-of-day column beside it joined into one in place (see the module docstring), and a note.

    ``time`` may name either of the two or both as joined (``Datum Zeit``, as the model file keeps it). Where
    no column is asked for, the first column named as a time that is one of such a pair is taken.

    Raises
    ------
    InputError
        A row whose date or time of day is empty, naming the row and the column.
    """
    stamp = _pair_named(frame, time)
    note = None
    if stamp is None:
        chosen, note = found_time_column(frame, time, label, default=default)
        stamp = _pair_of(frame, chosen)
        if stamp is None and note is not None:
            stamp = next(filter(None, (_pair_of(frame, name) for name in time_like_columns(frame.columns))), None)
        if stamp is None:
            return chosen, note
    joined = _joined(frame, stamp, label)
    if joined == time:
        return joined, None
    unasked = f" (there is no '{time}'; --time names another)" if note is not None else ""
    return joined, (
        f"{label}: time from columns '{stamp.date}' and '{stamp.clock}', a date and a time of day read as one "
        f"stamp, '{joined}'{unasked}"
    )


def _pair_named(frame: pd.DataFrame, time: str) -> Stamp | None:
    """The pair whose joined name ``time`` is, when the frame has no column of that name."""
    names = [str(c) for c in frame.columns]
    if time in names:
        return None
    for date, clock in zip(names, names[1:]):
        if f"{date} {clock}" == time:
            stamp = _pair_of(frame, date)
            if stamp is not None and (stamp.date, stamp.clock) == (date, clock):
                return stamp
    return None


def _pair_of(frame: pd.DataFrame, column: str) -> Stamp | None:
    """The date column and the time-of-day column ``column`` is one of (None: it is neither, or its neighbour is
    not the other, or the frame already has a column of their joined name, or they make no stamp of every
    row, :func:`_joinable`)."""
    names = [str(c) for c in frame.columns]
    if column not in names:
        return None
    k = names.index(column)
    stamp = _stamp_at(frame, k) if k + 1 < len(names) else None
    if stamp is None and k > 0:
        stamp = _stamp_at(frame, k - 1)
    if stamp is None or f"{stamp.date} {stamp.clock}" in names:
        return None
    return stamp if _joinable(stamp) else None


def _stamp_at(frame: pd.DataFrame, k: int) -> Stamp | None:
    """Column ``k`` as dates and column ``k + 1`` as times of day, when they hold them (the first and the last
    written cell read in one of :data:`~groupfit.timestamps.DATE_FORMATS`, of
    :data:`~groupfit.timestamps.TIME_FORMATS`: a workbook's date cells, its time cells or fractions of a day
    under a name that marks a time)."""
    dates = _date_text(frame.iloc[:, k])
    if dates is None or _form_of(dates, DATE_FORMATS) is None:
        return None
    clock = frame.iloc[:, k + 1]
    times = _time_text(clock)
    if times is None or _form_of(times, TIME_FORMATS) is None:
        return None
    names = [str(c) for c in frame.columns]
    return Stamp(names[k], names[k + 1], dates, times, pd.api.types.is_numeric_dtype(clock))


def _joinable(stamp: Stamp) -> bool:
    """Whether the two columns make one stamp: a date on every row with a time of day (a date written on the
    first row alone, or missing on the last, leaves the time of day to be read alone, as before), numbers as
    fractions of a day only where the date changes (below a day, hours or minutes under ``Time`` read so
    too), and on a single date times that do not pass midnight (a start date over a clock that rolls over is
    no date of every row; going back an hour where summer time ends is no midnight)."""
    dates, times = stamp.dates, stamp.times
    if (dates.isna() & times.notna()).any():
        return False
    days = dates.dropna().nunique()
    if stamp.fractions and days < 2:
        return False
    if days > 1:
        return True
    seconds = _seconds_of_day(times.dropna())
    return seconds is not None and bool(np.all(np.diff(seconds) > -MIDNIGHT_STEP_S))


def _seconds_of_day(times: pd.Series) -> np.ndarray | None:
    """The times of day in seconds after midnight, read in the form of :func:`_form_of`; None when none reads."""
    form = _form_of(times, TIME_FORMATS)
    if form is None:
        return None
    clock = pd.to_datetime(times, format=form, errors="coerce")
    return (clock - clock.dt.normalize()).dt.total_seconds().to_numpy()


def _form_of(text: pd.Series, forms) -> str | None:
    """The first of ``forms`` the first and the last written cell read in, as the stamps of a time column are
    told (:func:`groupfit.timestamps.text_clock` names a cell between them that does not); None when none."""
    written = text.dropna()
    if written.empty:
        return None
    first, last = str(written.iloc[0]), str(written.iloc[-1])
    return next((form for form in forms if parses(first, form) and parses(last, form)), None)


def _date_text(cells: pd.Series) -> pd.Series | None:
    """A date column's cells as text (empty cells missing), a workbook's date (at midnight) as ``2026-10-24``;
    None for date-times with a time of day or numbers."""
    if pd.api.types.is_datetime64_any_dtype(cells):
        if getattr(cells.dt, "tz", None) is not None or not (cells.dropna() == cells.dropna().dt.normalize()).all():
            return None
        return cells.dt.strftime("%Y-%m-%d").astype("string")
    if pd.api.types.is_numeric_dtype(cells) or pd.api.types.is_bool_dtype(cells):
        return None
    return _text(cells.map(_iso_date, na_action="ignore") if cells.dtype == object else cells)


def _iso_date(cell):
    """A workbook's or a Parquet file's date (``datetime.date``, a date-time at midnight) as ``2026-10-24``."""
    if isinstance(cell, datetime.datetime):
        return cell.strftime("%Y-%m-%d") if cell == pd.Timestamp(cell).normalize() else str(cell)
    return cell.isoformat() if isinstance(cell, datetime.date) else cell


def _time_text(cells: pd.Series) -> pd.Series | None:
    """A time-of-day column's cells as text (empty cells missing): a workbook's time cells as ``20:00:00`` (with
    microseconds in every row where one has them), fractions of a day under a name that marks a time and no
    unit (``Zeit`` 0.8333…) as ``20:00:00.000``; None for other numbers."""
    if pd.api.types.is_bool_dtype(cells) or pd.api.types.is_datetime64_any_dtype(cells):
        return None
    if pd.api.types.is_numeric_dtype(cells):
        return _day_fractions(cells)
    if cells.dtype == object:
        times = cells.dropna()
        if len(times) and all(isinstance(t, datetime.time) for t in times):
            spec = "microseconds" if any(t.microsecond for t in times) else "seconds"
            return _text(cells.map(lambda t: t.isoformat(timespec=spec), na_action="ignore"))
    return _text(cells)


def _day_fractions(cells: pd.Series) -> pd.Series | None:
    """Fractions of a day (a spreadsheet's time of day saved as a number) as ``20:00:00.000``, to the millisecond;
    None unless the column's name marks a time and gives no unit, and every number lies in [0, 1)."""
    name = str(cells.name)
    if not time_like_columns([name]) or named_time_unit(name) is not None:
        return None
    days = cells.to_numpy(dtype=float)
    written = days[np.isfinite(days)]
    if not written.size or written.min() < 0.0 or written.max() >= 1.0:
        return None
    millis = np.round(np.nan_to_num(days) * 86_400_000.0).astype(np.int64)
    text = [f"{m // 3_600_000:02d}:{m // 60_000 % 60:02d}:{m // 1000 % 60:02d}.{m % 1000:03d}" for m in millis]
    return pd.Series(text, index=cells.index, dtype="string").where(np.isfinite(days))


def _text(cells: pd.Series) -> pd.Series:
    """The cells as stripped text, empty ones missing."""
    text = cells.astype("string").str.strip()
    return text.mask(text == "")


def _joined(frame: pd.DataFrame, stamp: Stamp, label: str) -> str:
    """Replace the two columns by one of their stamps (``date time``) where the date column stood, in place;
    its name."""
    empty = (stamp.dates.isna() | stamp.times.isna()).to_numpy()
    if empty.any():
        row = int(np.argmax(empty))
        column = stamp.date if pd.isna(stamp.dates.iloc[row]) else stamp.clock
        raise InputError(f"{label}: row {row + 1}, column '{column}' is empty; fix or remove that row")
    stamps = [str(text) for text in stamp.dates + " " + stamp.times]
    position = [str(c) for c in frame.columns].index(stamp.date)
    del frame[frame.columns[position + 1]]
    del frame[frame.columns[position]]
    name = f"{stamp.date} {stamp.clock}"
    frame.insert(position, name, pd.Series(stamps, index=frame.index))
    return name


__all__ = ["found_stamp_column"]
