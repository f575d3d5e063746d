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
from datetime import datetime, timezone

import numpy as np
import pandas as pd

from groupfit.timestamps import ZONE_HOURS, ZONE_NAME, hour_off

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


def _offset_s(wall_s: float, zone: zoneinfo.ZoneInfo, fold: int) -> float:
    wall = datetime.fromtimestamp(wall_s, tz=timezone.utc).replace(tzinfo=zone, fold=fold)
    return wall.utcoffset().total_seconds()


def _changing_zones(before_s: float, after_s: float, hours: int) -> tuple[str, ...]:
    """The zones whose UTC offset grows by ``hours`` between two wall-clock times (the later one the second
    reading of a repeated hour where the clock went back)."""
    fold_after = 1 if hours < 0 else 0
    return tuple(
        zone.key
        for zone in _zones()
        if _offset_s(after_s, zone, fold_after) - _offset_s(before_s, zone, 0) == 3600.0 * hours
    )


def summer_time_changes(wall_s: np.ndarray) -> list[ClockChange]:
    """The changes to and from summer time in a column of naive date-times.

    Parameters
    ----------
    wall_s : ndarray
        Each row's wall-clock date-time in seconds since 1970, read as if it were UTC.

    Returns
    -------
    list of ClockChange
        Every step of an hour more or less than the sampling period that some time zone's clock takes between
        the two rows; empty where there is none, the clock is sampled every half hour or slower, or no tz
        database is at hand.
    """
    wall_s = np.asarray(wall_s, dtype=float)
    step = np.diff(wall_s)
    forward = step[step > 0]
    if not forward.size:
        return []
    period = float(np.median(forward))
    changes = []
    for hours in (1, -1):
        for i in np.flatnonzero(hour_off(step, period, hours)):
            zones = _changing_zones(float(wall_s[i]), float(wall_s[i + 1]), hours)
            if zones:
                changes.append(ClockChange(int(i) + 1, hours, zones))
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
        others = f" and {len(change.zones) - 1} other zones" if len(change.zones) > 1 else ""
        told.append(
            f"goes {went} an hour at row {change.row + 1} ({stamp(wall_s[change.row - 1])} → "
            f"{stamp(wall_s[change.row])}: summer time {began}, as in {change.zone}{others}), the rows before it "
            f"read an hour {moved}"
        )
    return (
        f"{label}: the clock in column '{column}' is local time without a UTC offset and {'; it '.join(told)}, so "
        "that the run keeps its period (write the stamps with their UTC offset, e.g. 2026-10-25T02:00:00+01:00, "
        "to place them yourself)"
    )


def through_clock_changes(
    raw: pd.Series, seconds: np.ndarray, origin_s: float, label: str, column: str
) -> tuple[np.ndarray, float, str | None]:
    """A date-time column read as seconds since its first row (``seconds``, the first row ``origin_s`` since
    1970), read through its clock's changes to and from summer time when it names no zone: the seconds, the
    first row's date-time in the clock of the last row, and the note (None where nothing changed)."""
    wall_s = origin_s + np.asarray(seconds, dtype=float)
    changes = summer_time_changes(wall_s) if names_no_zone(raw) else []
    if not changes:
        return seconds, origin_s, None
    shifted = read_through(wall_s, changes)
    return shifted - shifted[0], float(shifted[0]), change_note(label, column, wall_s, changes)


__all__ = [
    "ClockChange",
    "change_note",
    "names_no_zone",
    "read_through",
    "summer_time_changes",
    "through_clock_changes",
]
