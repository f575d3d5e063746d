"""Elapsed times written with colons: ``h:mm:ss`` past a day, durations led by days, and two fields
(``m:ss`` or ``h:mm``).

A logger or a spreadsheet that counts the time since the start of a test
writes it as ``26:40:00`` (a spreadsheet's ``[h]:mm:ss``), ``1 day, 2:40:00``
(Python or pandas), or in two fields: ``75:30`` (minutes and seconds, a
stop-watch's reading) or ``26:40`` (hours and minutes). Two fields read as a
time of day while the first stays within 0…23; beyond it they are an elapsed
time, and which of the two only the column's name can say (``Zeit [min]``,
``time [mm:ss]``, ``elapsed (h)``, ``Dauer [hh:mm]``), or a fraction of the
second field (``75:30.5``: seconds have fractions, minutes in ``h:mm`` do
not).
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from groupfit.errors import InputError

DAY_S = 86400.0
ELAPSED = re.compile(r"(?:(\d+)\s*(?:days?|d),?\s+)?(\d+):([0-5]\d):([0-5]\d(?:[.,]\d+)?)", re.IGNORECASE)
"""An elapsed time ``h:mm:ss`` whose hours run past 23 (a spreadsheet's ``[h]:mm:ss``), or led by days
(``1 day, 2:00:00``, ``0 days 00:00:15``, ``2d 03:00:00``: a duration as Python or pandas writes it)."""
TWO_FIELDS = re.compile(r"(\d+):([0-5]\d(?:[.,]\d+)?)")
"""``m:ss`` or ``h:mm``: a first field of any size, a second of 00…59 (seconds may carry a fraction)."""
MINUTES_SECONDS = re.compile(r"(?<![a-z])(?:m{1,2}|min)\s*:\s*(?:s{1,2}|sec|sek)(?![a-z])", re.IGNORECASE)
"""A name that gives the form ``m:ss`` (``time [mm:ss]``, ``Zeit (min:sek)``)."""
HOURS_MINUTES = re.compile(r"(?<![a-z])(?:h{1,2}|std)\s*:\s*(?:m{1,2}|min)(?![a-z])", re.IGNORECASE)
"""A name that gives the form ``h:mm`` (``elapsed [hh:mm]``, ``Dauer (Std:Min)``)."""
LAST_TIME_OF_DAY_HOUR = 23


def elapsed_seconds(text: pd.Series) -> np.ndarray | None:
    """Seconds since the first row of a column of elapsed times ``[d days] h:mm:ss`` (hours beyond 23
    allowed); None when a cell is not one."""
    found = text.str.extract("^" + ELAPSED.pattern + "$", flags=ELAPSED.flags)
    if bool(found[1].isna().any()):
        return None
    seconds = (
        found[0].fillna("0").astype(float) * DAY_S
        + found[1].astype(float) * 3600.0
        + found[2].astype(float) * 60.0
        + found[3].str.replace(",", ".", regex=False).astype(float)
    ).to_numpy(dtype=float)
    return seconds - seconds[0]


def first_field_seconds(name: str, named_unit_s: float | None) -> float | None:
    """Seconds of the first of two fields by the column's name: 60 (``m:ss``) or 3600 (``h:mm``); None when
    the name says neither. ``named_unit_s``: the seconds of the unit of time the name ends in, if any."""
    if MINUTES_SECONDS.search(name):
        return 60.0
    if HOURS_MINUTES.search(name):
        return 3600.0
    return named_unit_s if named_unit_s in (60.0, 3600.0) else None


def two_field_seconds(text: pd.Series, name: str, label: str, named_unit_s: float | None) -> np.ndarray | None:
    """Seconds since the first row of a column of two-field elapsed times (module docstring); None when a
    cell is not of two fields, or when the column reads as a time of day ``hh:mm`` (the name gives no form,
    no second has a fraction, and no first field passes 23).

    Raises
    ------
    InputError
        The first field passes 23 and neither the name nor a fraction says whether the fields are minutes
        and seconds or hours and minutes: guessing would read the run 60 times too fast or too slow.
    """
    found = text.str.extract("^" + TWO_FIELDS.pattern + "$")
    if bool(found[0].isna().any()):
        return None
    first = found[0].astype(float).to_numpy(dtype=float)
    second_text = found[1].str.replace(",", ".", regex=False)
    second = second_text.astype(float).to_numpy(dtype=float)
    unit_s = first_field_seconds(name, named_unit_s)
    if unit_s is None and bool(second_text.str.contains(".", regex=False).any()):
        unit_s = 60.0
    if unit_s is None:
        past = np.flatnonzero(first > LAST_TIME_OF_DAY_HOUR)
        if not past.size:
            return None
        row = int(past[0])
        raise InputError(
            f"{label}: row {row + 1}, column '{name}': {str(text.iloc[row])!r} is an elapsed time of two "
            "fields, minutes:seconds or hours:minutes, and the column's name says neither; name it with its "
            f"form ('{name} [mm:ss]' or '{name} [hh:mm]') or convert it to seconds"
        )
    seconds = first * unit_s + second * (unit_s / 60.0)
    return seconds - seconds[0]


__all__ = ["DAY_S", "ELAPSED", "elapsed_seconds", "first_field_seconds", "two_field_seconds"]
