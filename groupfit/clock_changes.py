"""A logger's local clock changing to or from summer time, found in its naive date-times and read through.

A log stamped with the local wall-clock time and no UTC offset jumps an hour
ahead where summer time begins and goes an hour back where it ends. A long
thermal test runs over a weekend, when the clocks change, so such a log is
common. The step is read as a change of the clock, not a gap or rows out of
order, only when it is one: the rows before and after it are a period apart
in some time zone of the tz database, whose UTC offset changes by that hour
between the two wall-clock times (Europe/Berlin: 2026-03-29 01:59 → 03:00,
2026-10-25 02:59 → 02:00). The rows before the change are then read in the
wall-clock time of the rows after it, so the whole log is in the time its
last row keeps.
"""

from __future__ import annotations

import dataclasses
import functools
import zoneinfo
from datetime import datetime, timedelta, timezone

import numpy as np
import pandas as pd

from groupfit.timestamps import ZONE_HOURS, ZONE_NAME, stamp_resolution

HOUR = timedelta(hours=1)
MISSED_PERIODS = 3
"""Samples a change of the clock may coincide with missing: as many in a row as ``--resample`` interpolates
(``groupfit.resample.GAP_PERIODS``)."""

WELL_KNOWN_ZONES = (
    "Europe/Berlin",
    "Europe/London",
    "America/New_York",
    "America/Chicago",
    "America/Denver",
    "America/Los_Angeles",
    "Europe/Helsinki",
    "Australia/Sydney",
    "America/Sao_Paulo",
    "Pacific/Auckland",
)
"""The zone a note names first when several change their clocks at the same wall-clock time."""


@dataclasses.dataclass(frozen=True)
class ClockChange:
    """A change of a local clock between two rows.

    Attributes
    ----------
    row : int
        The first row (0-based) after the change.
    hours : int
        +1 where the clock went ahead (summer time began), −1 where it went back (it ended).
    zones : tuple of str
        The time zones whose clocks changed so between the two rows' wall-clock times.
    """

    row: int
    hours: int
    zones: tuple[str, ...]

    @property
    def zone(self) -> str:
        """The zone to name: a well-known one among :attr:`zones`, else the first."""
        return next((z for z in WELL_KNOWN_ZONES if z in self.zones), self.zones[0])


@functools.lru_cache(maxsize=1)
def _zones() -> tuple[zoneinfo.ZoneInfo, ...]:
    """Every zone of the tz database at hand (none where the system and the ``tzdata`` package lack it)."""
    zones = []
    for key in sorted(zoneinfo.available_timezones()):
        try:
            zones.append(zoneinfo.ZoneInfo(key))
        except (zoneinfo.ZoneInfoNotFoundError, ValueError, OSError):
            continue
    return tuple(zones)


def _placed(wall_s: float, zone: zoneinfo.ZoneInfo, fold: int) -> datetime | None:
    """A wall-clock time in ``zone`` (``fold`` 1: the second reading of a repeated hour); None where the zone's
    clock skips it (the hour summer time begins with)."""
    wall = datetime.fromtimestamp(wall_s, tz=timezone.utc).replace(tzinfo=zone, fold=fold)
    there = wall.astimezone(timezone.utc).astimezone(zone)
    return wall if there.replace(tzinfo=None) == wall.replace(tzinfo=None) else None


def _changing_zones(before_s: float, after_s: float, hours: int) -> tuple[str, ...]:
    """The zones whose clock shows both wall-clock times and whose UTC offset grows by ``hours`` between them
    (the later one the second reading of a repeated hour where the clock went back)."""
    zones = []
    for zone in _zones():
        before, after = _placed(before_s, zone, 0), _placed(after_s, zone, 1 if hours < 0 else 0)
        if before is not None and after is not None and after.utcoffset() - before.utcoffset() == HOUR * hours:
            zones.append(zone.key)
    return tuple(zones)


def _candidate_steps(step: np.ndarray, period: float) -> list[tuple[int, int]]:
    """``(row before, hours)`` of the steps an hour's change of the clock may explain: read an hour shorter (it
    went ahead) or longer (back), they come to a period, or up to :data:`MISSED_PERIODS` more where
    samples were missed there, to 2 % of the period, the stamps' rounding
    (:func:`~groupfit.timestamps.stamp_resolution`) or the most the clock's other steps stray from the period."""
    near_an_hour = np.abs(step) > 0.5 * 3600.0
    if not near_an_hour.any():
        return []
    ordinary = step[np.abs(step - period) < 0.5 * period]
    jitter = float(np.max(np.abs(ordinary - period))) if ordinary.size else 0.0
    resolution = stamp_resolution(np.concatenate([[0.0], np.cumsum(np.abs(step))]), period)
    spare = max(0.02 * period, resolution, jitter) + 1e-6  # date-times in seconds since 1970 keep about 1e-7 s
    found = []
    for hours in (1, -1):
        corrected = step - 3600.0 * hours
        periods = np.round(corrected / period)
        fits = (periods >= 1) & (periods <= MISSED_PERIODS + 1) & (np.abs(corrected - periods * period) <= spare)
        found += [(int(i), hours) for i in np.flatnonzero(fits & near_an_hour)]
    return found


def summer_time_changes(wall_s: np.ndarray) -> list[ClockChange]:
    """The changes to and from summer time in a column of naive date-times.

    Parameters
    ----------
    wall_s : ndarray
        Each row's wall-clock date-time in seconds since 1970, read as if it were UTC.

    Returns
    -------
    list of ClockChange
        Every step that, an hour shorter or longer, comes to one sampling period (or a few, where samples were
        missed there) and that some time zone's clock takes between the two rows; empty where there is none,
        the clock is sampled every half hour or slower, or no tz database is at hand.
    """
    wall_s = np.asarray(wall_s, dtype=float)
    step = np.diff(wall_s)
    forward = step[step > 0]
    if not forward.size:
        return []
    period = float(np.median(forward))
    if period >= 1800.0:
        return []
    changes = []
    for i, hours in _candidate_steps(step, period):
        zones = _changing_zones(float(wall_s[i]), float(wall_s[i + 1]), hours)
        if zones:
            changes.append(ClockChange(i + 1, hours, zones))
    return sorted(changes, key=lambda change: change.row)


def read_through(wall_s: np.ndarray, changes: list[ClockChange]) -> np.ndarray:
    """The wall-clock times with the rows before each change moved into the clock the rows after it keep."""
    shifted = np.asarray(wall_s, dtype=float).copy()
    for change in changes:
        shifted[: change.row] += 3600.0 * change.hours
    return shifted


def names_no_zone(raw: pd.Series) -> bool:
    """Whether a date-time column is local time with nothing that places it: no time zone on a date-time
    type, no UTC offset in its text (``2026-10-25T02:00:00+01:00``) and no zone named after it (``CEST``)."""
    if pd.api.types.is_datetime64_any_dtype(raw):
        return getattr(raw.dt, "tz", None) is None
    first = str(raw.iloc[0]).strip()
    named = ZONE_NAME.match(first)
    if named and named.group(2).lower() in ZONE_HOURS:
        return False
    try:
        return pd.Timestamp(first).tzinfo is None
    except (ValueError, TypeError, OverflowError):
        return True


def change_note(label: str, column: str, wall_s: np.ndarray, changes: list[ClockChange]) -> str:
    """The note that names each change, a zone whose clock made it and how the rows before it were read."""

    def stamp(seconds: float) -> str:
        return datetime.fromtimestamp(seconds, tz=timezone.utc).strftime("%Y-%m-%d %H:%M:%S")

    told = []
    for change in changes:
        went, began, moved = ("ahead", "began", "later") if change.hours > 0 else ("back", "ended", "earlier")
        others = len(change.zones) - 1
        also = f" and {others} other zone{'s' if others > 1 else ''}" if others else ""
        told.append(
            f"goes {went} an hour at row {change.row + 1} ({stamp(wall_s[change.row - 1])} → "
            f"{stamp(wall_s[change.row])}: summer time {began}, as in {change.zone}{also}), the rows before it "
            f"read an hour {moved}"
        )
    last = changes[-1]
    placed = _placed(float(wall_s[last.row]), zoneinfo.ZoneInfo(last.zone), 1 if last.hours < 0 else 0)
    example = placed.isoformat() if placed is not None else "2026-10-25T02:00:00+01:00"
    return (
        f"{label}: the clock in column '{column}' is local time without a UTC offset and {'; it '.join(told)}, so "
        f"that the run keeps its period (write the stamps with their UTC offset, e.g. {example}, to place them "
        "yourself)"
    )


CLOCK_SHIFTS = "clock_shifts"
"""``frame.attrs`` key: where a local clock without a UTC offset changed, ``(seconds, shift_s)`` for each change
— the first row after it, in seconds since the first row, and the seconds the rows before it were moved
(:func:`shift_at`); empty where the clock did not change, None (or no key) where the stamps place themselves."""


def through_clock_changes(
    raw: pd.Series, seconds: np.ndarray, origin_s: float, label: str, column: str
) -> tuple[np.ndarray, float, str | None, tuple[tuple[float, float], ...] | None]:
    """A date-time column read as seconds since its first row (``seconds``, the first row ``origin_s`` since
    1970), read through its clock's changes to and from summer time when it names no zone: the seconds, the
    first row's date-time in the clock of the last row, the note (None where nothing changed) and the changes
    as :data:`CLOCK_SHIFTS` keeps them (None where the column names its zone)."""
    if not names_no_zone(raw):
        return seconds, origin_s, None, None
    wall_s = origin_s + np.asarray(seconds, dtype=float)
    changes = summer_time_changes(wall_s)
    if not changes:
        return seconds, origin_s, None, ()
    shifted = read_through(wall_s, changes)
    elapsed = shifted - shifted[0]
    shifts = tuple((float(elapsed[change.row]), 3600.0 * change.hours) for change in changes)
    return elapsed, float(shifted[0]), change_note(label, column, wall_s, changes), shifts


def shift_at(shifts: tuple[tuple[float, float], ...] | None, time_s: float) -> float | None:
    """The seconds a local clock's changes (:data:`CLOCK_SHIFTS`) added to the wall-clock time of the row at
    ``time_s`` (seconds since the first row, in the last row's clock) to put it in the last row's clock; None
    where the stamps place themselves."""
    if shifts is None:
        return None
    return float(sum(shift for at, shift in shifts if time_s < at))


def change_between(before_s: float, after_s: float, period_s: float, spare_s: float) -> bool:
    """Whether a local clock that showed ``before_s`` at one row and ``after_s`` (wall-clock date-times in seconds
    since 1970, read as if UTC) at the next went ahead or back an hour between them: the step, an hour shorter or
    longer, comes to ``period_s`` within ``spare_s``, and some zone's clock changes so there (two files of one
    log cut where the clock changed)."""
    if not 0.0 < period_s < 1800.0:
        return False
    for hours in (1, -1):
        if abs(after_s - before_s - 3600.0 * hours - period_s) <= spare_s:
            return bool(_changing_zones(before_s, after_s, hours))
    return False


__all__ = [
    "CLOCK_SHIFTS",
    "ClockChange",
    "change_between",
    "change_note",
    "names_no_zone",
    "read_through",
    "shift_at",
    "summer_time_changes",
    "through_clock_changes",
]
