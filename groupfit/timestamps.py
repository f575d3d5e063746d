"""A time column in seconds: text date-times (``2026-03-02 08:00:00``, ``02.03.2026 08:00:00`` …), or numbers
in the unit the column's name gives (``time_ms``, ``Zeit [min]``, ``elapsed_h``; seconds when it names none).

A logger's CSV often stamps its rows with the wall-clock time rather than
seconds. The forms read are ISO 8601 (``T`` or a space, fractions of a
second, a UTC offset), and a date in one of :data:`DATE_FORMATS` followed by
a time of day in one of :data:`TIME_FORMATS`, or a time of day alone (a log
that passes midnight then counts on into the next day).

Where a column reads in more than one form (``03/02/2026`` is 3 February or
2 March), the form whose times increase most evenly wins: a log's samples
are spaced alike, and the wrong reading of day and month puts a month
between two of them. Where the forms agree on every interval they give the
same seconds.
"""

from __future__ import annotations

import re
from datetime import datetime

import numpy as np
import pandas as pd

from groupfit.elapsed_times import DAY_S, elapsed_seconds, two_field_seconds
from groupfit.errors import InputError
from groupfit.textlayout import is_number

DATE_FORMATS = (
    "%Y-%m-%d",
    "%Y/%m/%d",
    "%d.%m.%Y",
    "%d.%m.%y",
    "%d/%m/%Y",
    "%m/%d/%Y",
    "%d/%m/%y",
    "%m/%d/%y",
    "%d-%m-%Y",
    "%d-%m-%y",
    "%d-%b-%Y",
    "%d-%b-%y",
    "%d %b %Y",
    "%b %d %Y",
    "%Y.%m.%d",
    "%Y年%m月%d日",
)
"""Dates as loggers write them; a two-digit year after the four-digit ones (a HOBO logger's ``03/01/26``),
English month names (``01-Mar-2026``), and a Chinese or Japanese date (``2026年3月2日``)."""
TIME_FORMATS = (
    "%H:%M:%S.%f",
    "%H:%M:%S,%f",
    "%H:%M:%S:%f",
    "%H:%M:%S",
    "%H:%M",
    "%I:%M:%S.%f %p",
    "%I:%M:%S %p",
    "%I:%M %p",
)
DATE_TIME_JOINERS = (" ", "-", "_", ", ")
"""What loggers write between a stamp's date and its time of day: a space, a hyphen or an underscore (a script's
``2021/06/05-13:24:41``, ``2026-03-02_08:00:00``), a comma (a browser's ``3/2/2026, 8:00:00 AM``)."""
FORMATS = tuple(f"{d}{j}{t}" for d in DATE_FORMATS for j in DATE_TIME_JOINERS for t in TIME_FORMATS) + TIME_FORMATS
"""Every form tried after ISO 8601, in order; the time-of-day forms last."""
EXAMPLES = "2026-03-02 08:00:00, 2026-03-02T08:00:00+01:00, 02.03.2026 08:00:00, 03/02/2026 8:00:00 AM, 08:00:00"
UNIT_SECONDS = {
    **dict.fromkeys(("ms", "msec", "millisecond", "milliseconds", "millisekunden", "毫秒", "ミリ秒", "мс"), 1e-3),
    **dict.fromkeys(("s", "sec", "secs", "second", "seconds", "sek", "sekunden", "秒", "초", "с", "сек"), 1.0),
    **dict.fromkeys(("min", "mins", "minute", "minutes", "minuten", "分", "分钟", "분", "мин"), 60.0),
    **dict.fromkeys(("h", "hr", "hrs", "hour", "hours", "std", "stunde", "stunden", "小时", "ч"), 3600.0),
    **dict.fromkeys(("d", "day", "days", "tag", "tage", "天"), 86400.0),
}
"""Units a time column's name may end in (``time_ms``, ``Zeit [min]``, ``Zeit [Std]``, ``hours``), and their
seconds; an abbreviation may end in a dot (``Zeit [Min.]``)."""
NAMED_UNIT = re.compile(
    r"(?:^|[_\s\[(/（［])\s*([a-z]+|毫秒|ミリ秒|秒|分钟|分|小时|天|초|분|мс|сек|мин|с|ч)\.?\s*[\])）］]?\s*$",
    re.IGNORECASE,
)
BRACKETED_UNIT = re.compile(r"[\[(（［]\s*([a-z]{1,12})\.?\s*[\])）］]\s*$", re.IGNORECASE)
"""A unit in brackets at the end of a name (``Zeit [xyz]``): a time column's must be one of :data:`UNIT_SECONDS`."""
TIME_ZONES = frozenset({"utc", "gmt", "z", "local", "lt", "cet", "cest", "mez", "mesz", "est", "pst"})
"""Bracketed words a time column's name may end in that are not units (``Time (UTC)``)."""
LONG_TIME = r"(?:[a-z]+[\s_-]){2,3}(?:time|zeit)(?=\s*[\[(]\s*(?:" + "|".join(UNIT_SECONDS) + r")\.?\s*[\])])"
"""A time named in several words and a unit (``Scan Sweep Time (Sec)``; after ``Time`` beside ``Run Time (s)``)."""
TIME_NAME = re.compile(
    r"^\s*(?:date[\s_-]?time|time[\s_-]?stamp|datum[\s_-]?zeit|zeitstempel|zeitpunkt|datum|date|" + LONG_TIME + "|"
    r"(?:[a-z]+[\s_-]?)?(?:time|zeit)|elapsed|x_value|ts|seconds|secs?|sekunden|minutes|minuten|hours|stunden|"
    r"horodatage|temps(?![\s_-]*[\[(]?\s*(?:°|c(?![a-z])|deg))|tiempo|tempo|fecha|heure|"
    r"[\u3040-\u30ff\u4e00-\u9fff]{0,8}?(?:时间|時間|时刻|時刻|日时|日時|日期|日付)|"
    r"(?:[\uac00-\ud7a3]{1,8}\s)?[\uac00-\ud7a3]{0,8}?(?:시간|시각|일시|날짜)|"
    r"(?:[\u0400-\u04ff]{1,12}\s)?(?:время|дата))"
    r"(?=$|[^a-z0-9])",
    re.IGNORECASE,
)
"""Names a logger gives its time column (``Timestamp``, ``Date/Time``, ``Zeit [min]``, ``elapsed_h``, ``Relative
Time``, ``Laufzeit [s]``, ``Seconds``, ``Temps (s)``, ``Horodatage``, ``Tiempo``, LabVIEW's ``X_Value``, a JSON
log's ``ts``, ``时间``, ``経過時間``, ``日時``, ``경과시간``, ``일시``, ``Время``, ``Дата и время``)."""
OF_DAY = re.compile(r"\bof[\s_-]+day\s*$", re.IGNORECASE)
"""A time of day (``Time of day``): its last word is no unit."""
BARE_T = re.compile(r"^\s*t\s*(?:[_\s\[(/]\s*(?:" + "|".join(UNIT_SECONDS) + r")\s*[\])]?)?\s*$", re.IGNORECASE)
"""``t``, ``t_s``, ``t [min]``: a lone t with a unit or none (not ``T1`` or ``T_amb``, which are sensors)."""


def time_like_columns(columns) -> list[str]:
    """The columns whose names say they hold the time, in table order, a long name (:data:`LONG_TIME`) last."""
    named = [str(c) for c in columns if TIME_NAME.match(str(c)) or BARE_T.match(str(c))]
    return sorted(named, key=lambda name: re.match(r"^\s*" + LONG_TIME, name, re.IGNORECASE) is not None)


EPOCH_UNITS = (
    (1e12, 1e13, 1e-3, "Unix times in milliseconds"),
    (1e15, 1e16, 1e-6, "Unix times in microseconds"),
    (1.2e17, 2.2e17, 1e-7, "Windows file times (100 ns since 1601)"),
    (1e18, 1e19, 1e-9, "Unix times in nanoseconds"),
)
"""Unix times of 2001 … 2286 in ms, µs and ns, and Windows FILETIME stamps of 1981 … 2286 (a controller's log):
far beyond any time in seconds, so read in their unit."""


def epoch_to_seconds(frame: pd.DataFrame, column: str, label: str) -> str | None:
    """A numeric time column of Unix times in ms, µs or ns or of Windows file times (its name giving no unit)
    converted to seconds in place, and its note (None: not one)."""
    values = numbers_without_unit(frame, column)
    if values is None or not values.size:
        return None
    for low, high, scale, unit in EPOCH_UNITS:
        if values.min() >= low and values.max() < high:
            frame[column] = values * scale
            return f"{label}: column '{column}' holds {unit}: read in seconds"
    return None


def numbers_without_unit(frame: pd.DataFrame, column: str) -> np.ndarray | None:
    """A numeric time column's finite values when its name gives no unit of time (None otherwise)."""
    if column not in frame.columns or names_a_unit(column) or not pd.api.types.is_numeric_dtype(frame[column]):
        return None
    values = frame[column].to_numpy(dtype=float)
    return values if np.all(np.isfinite(values)) else None


def names_a_unit(name: str) -> bool:
    """Whether a column's name ends in a unit of time (``time_s``, ``Zeit [min]``)."""
    return named_time_unit(name) is not None


def unit_seconds(name: str, label: str = "") -> float:
    """Seconds per unit of a numeric time column, from the unit its name ends in (1 when it names none).

    Raises
    ------
    InputError
        The name ends in a bracketed unit that is not one of time (``Zeit [xyz]``): guessing seconds would
        read the run on the wrong clock.
    """
    unit = named_time_unit(name)
    if unit:
        return UNIT_SECONDS[unit]
    bracketed = BRACKETED_UNIT.search(str(name))
    if bracketed and bracketed.group(1).lower() not in TIME_ZONES:
        raise InputError(
            f"{label}: column '{name}': '{bracketed.group(1)}' is not a unit of time groupfit reads (ms, s, min, "
            "h, d, or their names); rename the column with its unit, e.g. 'time_s' or 'Zeit [min]'"
        )
    return 1.0


def named_time_unit(name: str) -> str | None:
    """The unit of time a column's name ends in (a key of :data:`UNIT_SECONDS`), None when it names none."""
    found = None if OF_DAY.search(str(name)) else NAMED_UNIT.search(str(name))
    unit = found.group(1).lower() if found else None
    return unit if unit in UNIT_SECONDS else None


RESTART_PERIODS = 10
"""A clock that goes back by more than this many periods and goes on from there has started again (a logger
restarted), not a sample out of order or a bad cell."""


def hour_off(step, period: float, sign: int):
    """Where a step is the period an hour longer (``sign`` 1: summer time began) or shorter (−1: it ended), to 2 %
    of the period, on a clock sampled more often than every half hour."""
    return (np.abs(np.asarray(step, dtype=float) - (period + sign * 3600.0)) <= 0.02 * period + 1e-9) & (
        period < 1800.0
    )


def refuse_clock_change(time: np.ndarray, label: str, column: str) -> None:
    """Refuse a clock of local time that goes back by an hour less one period (daylight saving time ended),
    naming the row: a UTC offset on the stamps places the repeated hour. (A clock that jumps ahead by an hour
    is not told from a pause in the logging.)"""
    step = np.diff(time)
    forward = step[step > 0]
    if not forward.size:
        return
    period = float(np.median(forward))
    back = np.flatnonzero(hour_off(step, period, -1))
    if back.size:
        i = int(back[0]) + 1
        raise InputError(
            f"{label}: the clock in column '{column}' goes back one hour at row {i + 1} ({time[i - 1]:g} s to "
            f"{time[i]:g} s: daylight saving time ended?); write the time stamps with their UTC offset "
            "(2026-10-25T02:00:00+01:00) or in UTC"
        )


def restart_refusal(time: np.ndarray, i: int, label: str, column: str, *, resampling: bool = False) -> InputError:
    """The refusal of a clock that starts again at row ``i`` (0-based; :func:`clock_restart`): the parts are
    runs of their own (``resampling``: averaging would mix the two recordings)."""
    averaged = "resampling would average two recordings together: " if resampling else ""
    return InputError(
        f"{label}: the clock in column '{column}' starts again at row {i + 1} ({time[i]:g} s after "
        f"{time[i - 1]:g} s: the logger restarted?); {averaged}split the file before row {i + 1} and give the "
        "parts as runs of their own (a fit on both: --data part1.csv part2.csv; a replay: one part at a time)"
    )


def clock_restart(time: np.ndarray) -> int | None:
    """The row (0-based) where the clock first goes back, when it starts again there: it goes back by more than
    :data:`RESTART_PERIODS` typical periods and goes on below where it was (a logger restarted, two recordings
    in one file); None otherwise."""
    step = np.diff(time)
    forward = step[step > 0]
    if not forward.size or np.all(step >= 0):
        return None
    typical = float(np.median(forward))
    i = int(np.argmax(step < 0)) + 1
    after = time[i + 1 : i + 4]
    if time[i - 1] - time[i] > RESTART_PERIODS * typical and after.size and np.all(after < time[i - 1]):
        return i
    return None


def is_text(column: pd.Series) -> bool:
    return column.dtype == object or pd.api.types.is_string_dtype(column)


def text_seconds(column: pd.Series, name: str, label: str) -> np.ndarray | None:
    """Seconds since the first row of a text column of date-times; None when its first cell is a number."""
    clock = text_clock(column, name, label)
    return None if clock is None else clock[0]


def text_clock(column: pd.Series, name: str, label: str, read_through=None) -> tuple[np.ndarray, float | None] | None:
    """:func:`text_seconds` and the first row's date-time in seconds since 1970 (UTC when the stamps name their
    zone; None for times of day or elapsed times, which name no date); None when the first cell is a number.
    ``read_through(seconds, origin)``: the seconds of a dated reading read through a local clock's changes, by
    which readings of day and month are told apart (the date of 11/01/2026 on which the clock goes back).

    Raises
    ------
    InputError
        A cell empty, or not a date-time in the form of the others, named with its row; or a first
        cell that is neither a number nor a date-time in a form read here.
    """
    text = column.astype("string").str.strip()
    empty = np.flatnonzero((text.isna() | (text == "")).to_numpy())
    if empty.size:
        raise InputError(f"{label}: row {empty[0] + 1}, column '{name}' is empty; fix or remove that row")
    text, zone_hours = _without_zone_names(text)
    first, last = str(text.iloc[0]), str(text.iloc[-1])
    if is_number(first, ","):
        return None
    readings = [reading for reading in _readings(text, first, last, name, label) if reading[0] is not None]
    if not readings:
        bad = _first_unread(text)
        if bad is None:
            raise InputError(
                f"{label}: row 1, column '{name}': {first!r} is neither a number of seconds nor a date-time "
                f"in a form groupfit reads ({EXAMPLES}); convert the column to seconds, or name the time "
                "column with --time"
            )
        row, form = bad
        raise InputError(
            f"{label}: row {row + 1}, column '{name}': {str(text.iloc[row])!r} is not a date-time in the form "
            f"of the rows above it ({form}); fix or remove that row"
        )
    through = read_through if read_through is not None and not zone_hours.any() else (lambda seconds, origin: seconds)
    seconds, origin = min(readings, key=lambda r: _unevenness(r[0] if r[1] is None else through(r[0], r[1])))
    return seconds - 3600.0 * (zone_hours - zone_hours[0]), None if origin is None else origin - 3600.0 * zone_hours[0]


ZONE_HOURS = {
    **dict.fromkeys(("utc", "gmt", "z", "wet"), 0.0),
    **dict.fromkeys(("west", "bst", "cet", "mez"), 1.0),
    **dict.fromkeys(("cest", "mesz", "eet"), 2.0),
    "eest": 3.0,
    **{"est": -5.0, "edt": -4.0, "cst": -6.0, "cdt": -5.0, "mst": -7.0, "mdt": -6.0, "pst": -8.0, "pdt": -7.0},
    **dict.fromkeys(("jst", "kst"), 9.0),
}
"""Time zones a logger may name after its stamps (``2026-03-01 08:00:00 CET``), in hours ahead of UTC."""
ZONE_NAME = re.compile(r"^(.*\S)\s+([A-Za-z]{1,4})$")


def _without_zone_names(text: pd.Series) -> tuple[pd.Series, np.ndarray]:
    """The stamps without the time zone named after each (when every one names one), and each stamp's zone in
    hours ahead of UTC (zeros when none is named): a change from CET to CEST is a clock change, not a gap."""
    found = text.str.extract(ZONE_NAME.pattern)
    hours = found[1].str.lower().map(ZONE_HOURS)
    if bool(hours.isna().any()):
        return text, np.zeros(len(text))
    return found[0].astype("string"), hours.to_numpy(dtype=float)


def _readings(text: pd.Series, first: str, last: str, name: str, label: str):
    """``(seconds since the first row, the first row in seconds since 1970 or None)`` of every form that reads
    the column."""
    elapsed = elapsed_seconds(text)
    if elapsed is not None:
        yield elapsed, None
    unit = named_time_unit(name)
    two_fields = two_field_seconds(text, name, label, UNIT_SECONDS[unit] if unit else None)
    if two_fields is not None:  # before a time of day, which it equals unless it passes midnight
        yield two_fields, None
    try:
        stamps = pd.to_datetime(text, format="ISO8601", utc=True)
    except (ValueError, TypeError):
        stamps = None
    if stamps is not None:
        yield _since_first(stamps), stamps.iloc[0].timestamp()
        return
    for form in FORMATS:
        if not (parses(first, form) and parses(last, form)):
            continue
        try:
            stamps = pd.to_datetime(text, format=form)
        except (ValueError, TypeError):
            continue
        seconds = _since_first(stamps)
        yield (_past_midnight(seconds), None) if form in TIME_FORMATS else (seconds, stamps.iloc[0].timestamp())


def _first_unread(text: pd.Series) -> tuple[int, str] | None:
    """The first row no form of the first row reads, with that form; None when the first row reads in none."""
    first = str(text.iloc[0])
    forms = [form for form in FORMATS if parses(first, form)]
    if _is_iso(first):
        forms.insert(0, "ISO 8601")
    if not forms:
        return None
    form = forms[0]
    for row, value in enumerate(text.tolist()):
        if not (_is_iso(value) if form == "ISO 8601" else parses(value, form)):
            return row, form
    return None


def _since_first(stamps: pd.Series) -> np.ndarray:
    return (stamps - stamps.iloc[0]).dt.total_seconds().to_numpy(dtype=float)


def _past_midnight(seconds: np.ndarray) -> np.ndarray:
    """A time of day that falls back by most of a day has passed midnight: count on into the next day."""
    days = np.concatenate([[0.0], np.cumsum(np.diff(seconds) < -DAY_S / 2)])
    return seconds + DAY_S * days


def _unevenness(seconds: np.ndarray) -> tuple[bool, float]:
    steps = np.diff(seconds)
    if not steps.size:
        return (False, 0.0)
    return (bool(np.any(steps <= 0)), float(np.max(np.abs(steps - np.median(steps)))))


def parses(value: str, form: str) -> bool:
    try:
        datetime.strptime(value, form)
    except ValueError:
        return False
    return True


def _is_iso(value: str) -> bool:
    try:
        datetime.fromisoformat(value)
    except ValueError:
        return False
    return True


STAMP_RESOLUTIONS_S = (60.0, 1.0, 0.1, 0.01, 0.001)
"""Resolutions a log writes its time stamps to (whole minutes, seconds, tenths …), the coarsest first."""
RESOLUTION_SHARE = 0.1
"""A resolution up to this share of the period is taken as the stamps' rounding, not a missed sample."""


def stamp_resolution(time: np.ndarray, period_s: float | None = None) -> float:
    """How coarsely the time stamps are written (s): the coarsest of :data:`STAMP_RESOLUTIONS_S`, at most
    :data:`RESOLUTION_SHARE` of the period (any, when ``period_s`` is None), that every stamp is a whole
    multiple of, counted from the first (0: none).

    A logger every 10.4 s writing whole seconds stamps intervals of 10 and 11 s: a step of one resolution
    around the period is the stamps' rounding, not an irregular clock.
    """
    offsets = np.asarray(time, dtype=float) - float(time[0])
    for resolution in STAMP_RESOLUTIONS_S:
        if period_s is None or resolution <= RESOLUTION_SHARE * period_s:
            counts = offsets / resolution
            if np.all(np.abs(counts - np.round(counts)) <= 1e-3):
                return resolution
    return 0.0


SLOWEST_PERIOD_S = 3600.0
"""A period longer than this (s) is unlike a thermal log's: the time column may be in ms, and a note asks."""
SHORTEST_RUN_S = 1800.0
"""A run shorter than this (s) on a time column whose name gives no unit is unlike a thermal log's: the column
may count minutes or hours, and a note asks."""


def unit_notes(label: str, column: str, time: np.ndarray, period_s: float, *, unit_named: bool) -> tuple[str, ...]:
    """Notes asking for the time column's unit when the run's clock in seconds is unlike a thermal log's: a
    whole run shorter than :data:`SHORTEST_RUN_S` on a column whose name gives no unit (``unit_named`` False),
    a period longer than :data:`SLOWEST_PERIOD_S`."""
    notes = []
    span = float(time[-1] - time[0])
    if not unit_named and span < SHORTEST_RUN_S:
        days = (
            "; if it holds fractions of a day (a spreadsheet's time of day saved as a number), name it so "
            f"({column} [d])"
            if 0.0 <= float(np.min(time)) and float(np.max(time)) < 1.0
            else ""
        )
        notes.append(
            f"{label}: the run lasts {span:g} s by column '{column}', read in seconds as its name gives no unit: a "
            f"thermal run lasts hours; if the column counts minutes or hours, name it so (time_min, Zeit [h]){days}"
        )
    if period_s > SLOWEST_PERIOD_S:
        notes.append(
            f"{label}: one sample every {period_s:g} s ({period_s / 3600:.3g} h) in column '{column}': if its unit "
            "is not seconds, name it so (time_ms, Zeit [min]) or give --time another column"
        )
    return tuple(notes)


__all__ = [
    "hour_off",
    "RESOLUTION_SHARE",
    "STAMP_RESOLUTIONS_S",
    "DATE_FORMATS",
    "DATE_TIME_JOINERS",
    "EXAMPLES",
    "FORMATS",
    "TIME_FORMATS",
    "RESTART_PERIODS",
    "SHORTEST_RUN_S",
    "SLOWEST_PERIOD_S",
    "UNIT_SECONDS",
    "clock_restart",
    "is_text",
    "refuse_clock_change",
    "restart_refusal",
    "stamp_resolution",
    "text_clock",
    "text_seconds",
    "time_like_columns",
    "named_time_unit",
    "numbers_without_unit",
    "parses",
    "unit_notes",
    "unit_seconds",
]
