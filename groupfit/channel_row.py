"""A row of channel numbers under a log's header: a description of its columns, not a reading.

A data logger's export may write, under the names, the numbers of the channels the columns were read on
(``Time,Spindle,Bed,Column,Error`` over ``,101,102,103,``). Such a row holds no time, so it cannot be a reading,
and it is left out with a note when it is the first row, its time cell is empty or a label (``Kanal``), and its
other filled cells, two or more, are whole numbers that rise from column to column, each outside the range of
the readings below it (a channel ``101`` over temperatures near 20 °C). A row without a time that fits none of
this is left to be refused, naming it. Over a date column and a time-of-day column (``Date,Time`` over
``,,101,102,103`` or ``Ch,Ch,1,2,3``) both cells of the row are the time's (:mod:`groupfit.stamp_channel_row`).
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from groupfit.numbercells import as_numbers
from groupfit.readtable import LEFT_OUT_TAIL

LABEL = re.compile(r"[^\W\d_][^\W\d]*\.?")
"""A label in the time cell of a row of channel numbers (``Kanal``, ``Channel``, ``Ch.``)."""


def without_channel_row(frame: pd.DataFrame, time: str, label: str) -> tuple[pd.DataFrame, str | None]:
    """The log without a first row of channel numbers (see the module docstring), its time column read as
    numbers where the row's label alone was text, and the note naming the row (None: there was none).

    Parameters
    ----------
    frame
        The log as read, its header's names as columns.
    time
        The name of its time column.
    label
        The file, as errors and notes name it.
    """
    channels = channel_numbers(frame, (time,))
    if channels is None:
        return frame, None
    kept = frame.iloc[1:].reset_index(drop=True)
    if not pd.api.types.is_numeric_dtype(kept[time]):
        values = as_numbers(kept[time], frame.attrs.get("decimal", "."), time)
        if values is not None:
            kept[time] = values
    return kept, channel_row_note(label, channels)


def channel_row_note(label: str, channels: list[float]) -> str:
    """The note naming a first row of channel numbers left out."""
    shown = ", ".join(f"{number:g}" for number in channels)
    return (
        f"{label}: 1 row of channel numbers left out (row 1: {shown} under the header, without a time: a "
        f"description of the columns, not a reading){LEFT_OUT_TAIL}"
    )


def channel_numbers(frame: pd.DataFrame, times: tuple[str, ...]) -> list[float] | None:
    """The channel numbers of the log's first row, when it is a row of them, its cells in the columns ``times``
    (the time column, or a date column and a time-of-day column) each empty or a label; None otherwise."""
    if not set(times) <= set(frame.columns) or len(frame) < 3:
        return None
    if not all(label_or_empty(frame[time].iloc[0]) for time in times):
        return None
    numbers = []
    for column in frame.columns:
        cell = frame[column].iloc[0]
        if column in times or label_or_empty(cell, label=False):
            continue
        value = pd.to_numeric(pd.Series([cell]), errors="coerce").iloc[0]
        below = pd.to_numeric(frame[column].iloc[1:], errors="coerce").to_numpy(dtype=float)
        below = below[np.isfinite(below)]
        if not np.isfinite(value) or value != round(value) or (below.size and below.min() <= value <= below.max()):
            return None
        numbers.append(float(value))
    rising = all(later > earlier for earlier, later in zip(numbers, numbers[1:]))
    return numbers if len(numbers) >= 2 and rising else None


def label_or_empty(cell, *, label: bool = True) -> bool:
    """Whether a cell is empty or, with ``label``, holds a word without a digit (``Kanal``)."""
    if cell is None or (isinstance(cell, float) and np.isnan(cell)):
        return True
    text = str(cell).strip()
    return text in ("", "nan", "<NA>") or (label and LABEL.fullmatch(text) is not None)


__all__ = ["channel_numbers", "channel_row_note", "label_or_empty", "without_channel_row"]
