"""A row of channel numbers under a date column and a time-of-day column: left out before the two are joined.

A logger that writes the date and the time of day apart (``Date,Time,T1,T2,error_um``) may write, under the
names, the numbers of the channels the columns were read on (``,,101,102,103``, ``Ch,Ch,1,2,3``). The date and
the time of day of the rows below it are joined into one stamp (:mod:`groupfit.date_time_columns`), and the row
is told as a row of channel numbers under a time column is (:mod:`groupfit.channel_row`), its two time cells
each empty or a label: left out with a note, so that the log reads as it would without it. A first row that is
no such row is read as before (its empty date refused, naming it).
"""

from __future__ import annotations

import pandas as pd

from groupfit.channel_row import channel_numbers, channel_row_note, label_or_empty, without_channel_row
from groupfit.date_time_columns import found_stamp_column
from groupfit.errors import InputError


def found_time_without_channel_row(
    frame: pd.DataFrame, time: str, label: str, *, default: bool = False
) -> tuple[pd.DataFrame, str, str | None, str | None]:
    """The log without a first row of channel numbers, its time column as
    :func:`~groupfit.date_time_columns.found_stamp_column` finds it, the note on the time column and the note
    on the row left out (None: there was none).

    Parameters
    ----------
    frame
        The log as read, its header's names as columns; a date column and a time-of-day column are joined in
        place where the log has no row of channel numbers.
    time
        The time column asked for (``--time``).
    label
        The file, as errors and notes name it.
    default
        ``time`` is the default name, not one the user gave.

    Raises
    ------
    InputError
        As :func:`~groupfit.date_time_columns.found_stamp_column` does.
    """
    under_stamp = _under_date_and_time(frame, time, label, default=default)
    if under_stamp is not None:
        return under_stamp
    chosen, time_note = found_stamp_column(frame, time, label, default=default)
    kept, channel_note = without_channel_row(frame, chosen, label)
    return kept, chosen, time_note, channel_note


def _under_date_and_time(
    frame: pd.DataFrame, time: str, label: str, *, default: bool
) -> tuple[pd.DataFrame, str, str | None, str] | None:
    """The log read as :func:`found_time_without_channel_row` reads it, when its first row is one of channel
    numbers whose cells over the two columns joined on the rows below it are each empty or a label; None when
    there is no such row (nothing in ``frame`` changed)."""
    if len(frame) < 3 or not any(label_or_empty(cell) for cell in frame.iloc[0]):
        return None
    below = frame.iloc[1:].reset_index(drop=True).copy()
    try:
        joined, time_note = found_stamp_column(below, time, label, default=default)
    except InputError:
        return None
    pair = tuple(name for name in frame.columns if name not in below.columns)
    channels = channel_numbers(frame, pair) if len(pair) == 2 else None
    if channels is None:
        return None
    return below, joined, time_note, channel_row_note(label, channels)


__all__ = ["found_time_without_channel_row"]
