"""A time stamp split over two columns: a date-time in whole seconds, and its milliseconds in the next column.

Loggers that sample faster than once a second without writing fractions of
a second into their stamps give the milliseconds a column of their own
(Graphtec's GL series: ``Date&Time`` ``2026/03/02 08:00:00`` then ``ms``
``500``). Read alone, the stamps repeat within each second and the run is
refused as not increasing; read together they are the time.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from groupfit.readtable import datetimes_to_seconds

MILLISECOND_NAME = re.compile(
    r"^\s*[\[(]?\s*(?:ms|msec|millisec|millisecs|milliseconds?|millisekunden?)\.?\s*[\])]?\s*$", re.IGNORECASE
)
"""The name of a column holding a stamp's milliseconds alone (``ms``, ``msec``, ``[ms]``, ``Millisekunden``)."""


def with_milliseconds(frame: pd.DataFrame, column: str, label: str) -> str | None:
    """The time column ``column`` in seconds with the milliseconds of the column after it, in place, that
    column removed, and a note (None: the next column is not one of milliseconds).

    The column after the time column is one of milliseconds when its name says so
    (:data:`MILLISECOND_NAME`) and every cell is a whole number 0 … 999; it is added only to stamps in
    whole seconds (a stamp that carries its own fractions is left as it is).
    """
    columns = [str(c) for c in frame.columns]
    after = columns.index(column) + 1 if column in columns else len(columns)
    if after >= len(columns):
        return None
    following = frame.columns[after]
    if not MILLISECOND_NAME.match(str(following)):
        return None
    millis = pd.to_numeric(frame[following], errors="coerce").to_numpy(dtype=float)
    if not (np.isfinite(millis).all() and (millis == np.round(millis)).all()):
        return None
    if millis.min() < 0 or millis.max() > 999:
        return None
    datetimes_to_seconds(frame, column, label)
    if not pd.api.types.is_numeric_dtype(frame[column]):
        return None
    seconds = frame[column].to_numpy(dtype=float)
    stamped = seconds[np.isfinite(seconds)]
    if not (stamped == np.round(stamped)).all():
        return None
    frame[column] = seconds + (millis - millis[0]) / 1000.0
    del frame[following]
    if not millis.any():
        return None
    return f"{label}: time from column '{column}' with the milliseconds of column '{following}'"


__all__ = ["MILLISECOND_NAME", "with_milliseconds"]
