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

import numpy as np
import pandas as pd

from groupfit.default_columns import found_time_column
from groupfit.errors import InputError
from groupfit.timestamps import DATE_FORMATS, TIME_FORMATS, named_time_unit, parses, time_like_columns

MIDNIGHT_STEP_S = 2 * 3600.0
"""A time of day that goes back by more than this on one date passed midnight (a change to or from summer time
goes back an hour)."""
Pair = tuple[str, str]
"""The date column and the time-of-day column after it."""


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
    pair = _pair_named(frame, time)
    note = None
    if pair is None:
        chosen, note = found_time_column(frame, time, label, default=default)
        pair = _pair_of(frame, chosen)
        if pair is None and note is not None:
            pair = next(filter(None, (_pair_of(frame, name) for name in time_like_columns(frame.columns))), None)
        if pair is None:
            return chosen, note
    joined = _joined(frame, pair, label)
    if joined == time:
        return joined, None
    unasked = f" (there is no '{time}'; --time names another)" if note is not None else ""
    return joined, (
        f"{label}: time from columns '{pair[0]}' and '{pair[1]}', a date and a time of day read as one stamp, "
        f"'{joined}'{unasked}"
    )


def _pair_named(frame: pd.DataFrame, time: str) -> Pair | None:
    """The pair whose joined name ``time`` is, when the frame has no column of that name."""
    names = [str(c) for c in frame.columns]
    if time in names:
        return None
    return next(
        (
            (date, clock)
            for date, clock in zip(names, names[1:])
            if f"{date} {clock}" == time and _pair_of(frame, date) == (date, clock)
        ),
        None,
    )


def _pair_of(frame: pd.DataFrame, column: str) -> Pair | None:
    """The date column and the time-of-day column ``column`` is one of (None: it is neither, or its neighbour is
    not the other, or the frame already has a column of their joined name)."""
    names = [str(c) for c in frame.columns]
    if column not in names:
        return None
    k = names.index(column)
    pair = None
    if k + 1 < len(names) and _holds_dates(frame.iloc[:, k]) and _holds_times_of_day(frame.iloc[:, k + 1]):
        pair = (names[k], names[k + 1])
    elif k > 0 and _holds_times_of_day(frame.iloc[:, k]) and _holds_dates(frame.iloc[:, k - 1]):
        pair = (names[k - 1], names[k])
    if pair is None or f"{pair[0]} {pair[1]}" in names:
        return None
    return pair if _joinable(frame[pair[0]], frame[pair[1]]) else None


def _joinable(date_cells: pd.Series, time_cells: pd.Series) -> bool:
    """Whether the two columns make one stamp: a date on every row with a time of day (a date written on the
    first row alone, or missing on the last, leaves the time of day to be read alone, as before), numbers as
    fractions of a day only where the date changes (below a day, hours or minutes under ``Time`` read so
    too), and on a single date times that do not pass midnight (a start date over a clock that rolls over is
    no date of every row; going back an hour where summer time ends is no midnight)."""
    dates, times = _date_text(date_cells), _time_text(time_cells)
    if (dates.isna() & times.notna()).any():
        return False
    days = dates.dropna().nunique()
    if pd.api.types.is_numeric_dtype(time_cells) and days < 2:
        return False
    if days > 1:
        return True
    seconds = _seconds_of_day(times.dropna())
    return seconds is not None and bool(np.all(np.diff(seconds) > -MIDNIGHT_STEP_S))


def _seconds_of_day(times: pd.Series) -> np.ndarray | None:
    """The times of day in seconds after midnight, read in the first of
    :data:`~groupfit.timestamps.TIME_FORMATS` that reads the first and the last; None when none does."""
    first, last = str(times.iloc[0]), str(times.iloc[-1])
    for form in TIME_FORMATS:
        if parses(first, form) and parses(last, form):
            clock = pd.to_datetime(times, format=form, errors="coerce")
            return (clock - clock.dt.normalize()).dt.total_seconds().to_numpy()
    return None


def _holds_dates(cells: pd.Series) -> bool:
    """Whether a column holds dates without a time of day (text in one of
    :data:`~groupfit.timestamps.DATE_FORMATS`, a workbook's date cells)."""
    text = _date_text(cells)
    return text is not None and _first_and_last_read(text, DATE_FORMATS)


def _holds_times_of_day(cells: pd.Series) -> bool:
    """Whether a column holds times of day (text in one of :data:`~groupfit.timestamps.TIME_FORMATS`, a
    workbook's time cells, fractions of a day under a name that marks a time)."""
    text = _time_text(cells)
    return text is not None and _first_and_last_read(text, TIME_FORMATS)


def _first_and_last_read(text: pd.Series, forms) -> bool:
    """Whether the first and the last written cell read in one of ``forms``, as the stamps of a time column are
    told (:func:`groupfit.timestamps.text_clock` names a cell between them that does not)."""
    written = text.dropna()
    if written.empty:
        return False
    first, last = str(written.iloc[0]), str(written.iloc[-1])
    return any(parses(first, form) and parses(last, form) for form in forms)


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


def _joined(frame: pd.DataFrame, pair: Pair, label: str) -> str:
    """Replace the two columns by one of their stamps (``date time``) where the date column stood, in place;
    its name."""
    date, clock = pair
    names = [str(c) for c in frame.columns]
    dates, times = _date_text(frame.iloc[:, names.index(date)]), _time_text(frame.iloc[:, names.index(clock)])
    empty = (dates.isna() | times.isna()).to_numpy()
    if empty.any():
        row = int(np.argmax(empty))
        column = date if pd.isna(dates.iloc[row]) else clock
        raise InputError(f"{label}: row {row + 1}, column '{column}' is empty; fix or remove that row")
    stamps = [str(stamp) for stamp in dates + " " + times]
    position = names.index(date)
    del frame[frame.columns[position + 1]]
    del frame[frame.columns[position]]
    name = f"{date} {clock}"
    frame.insert(position, name, pd.Series(stamps, index=frame.index))
    return name


__all__ = ["found_stamp_column"]
