"""Time stamps cut to whole minutes or seconds: several rows under each stamp, spread evenly within it.

A spreadsheet that saves a log with its default date format drops the
seconds (``2026/3/2 8:01`` for 08:01:15), and a fast logger with a coarse
clock stamps several readings with one second. Read as they are, the stamps
repeat and the run is refused as not increasing. When every row can be
placed on one uniform clock that falls, row by row, inside the minute (or
second) its stamp names, that clock is the run's: ``a + i·P`` with
``s_i ≤ a + i·P < s_i + R`` for every row ``i`` (stamp ``s_i``, resolution
``R``). The period ``P`` is taken from the stamps by least squares (rounded
to whole seconds, tenths … when that fits as well), the start ``a`` in the
middle of the starts every row allows. A log whose rows cannot all be so
placed (a duplicated row, a gap, two recordings) is left to be refused. The
stamps are taken as cut when most rows share theirs with another, or when
none does and they are coarser than a tenth of the period (a run every 100 s
stamped in whole minutes steps 60 and 120 s) but no whole multiple of it (a
run every 60 s stamped in whole minutes steps 60 s: a step of 120 s is a
missed sample). A uniform clock's cut stamps step by one of two neighbouring
numbers of stamps; a longer step is a gap, and refused.
"""

from __future__ import annotations

import math

import numpy as np

from groupfit.timestamps import RESOLUTION_SHARE, stamp_resolution

SHARED_SHARE = 0.8
"""Least share of the rows that share their stamp with another row for the stamps to be taken as cut."""


def spread_within_stamps(time: np.ndarray, label: str, column: str) -> tuple[np.ndarray, str | None]:
    """The rows' times spread evenly within their cut stamps, and a note (``time`` and None: not cut stamps)."""
    time = np.asarray(time, dtype=float)
    steps = np.diff(time)
    if time.size < 3 or np.any(steps < 0):
        return time, None
    resolution = stamp_resolution(time)
    if not resolution:
        return time, None
    rows = np.arange(time.size, dtype=float)
    fitted = float(np.polyfit(rows, time + resolution / 2, 1)[0])
    shared = np.r_[steps == 0, False] | np.r_[False, steps == 0]
    per_stamp = fitted / resolution
    coarse = not shared.any() and resolution > RESOLUTION_SHARE * fitted
    if (shared.mean() < SHARED_SHARE and not coarse) or (
        coarse and abs(per_stamp - round(per_stamp)) < 0.01 * per_stamp
    ):
        return time, None  # stamps as fine as the clock: a step of another length is a gap
    if not set(np.round(steps / resolution).astype(int)) <= {math.floor(per_stamp), math.floor(per_stamp) + 1}:
        return time, None  # a uniform clock's cut stamps step by one of two neighbouring whole stamps
    for period in dict.fromkeys((*(round(fitted, digits) for digits in range(4)), fitted)):
        if period <= 0:
            continue
        lowest, highest = float(np.max(time - rows * period)), float(np.min(time + resolution - rows * period))
        if lowest < highest:
            start = (lowest + highest) / 2
            spread = start + rows * period
            unit = {60.0: "minutes", 1.0: "seconds"}.get(resolution, f"multiples of {resolution:g} s")
            return spread - spread[0], (
                f"{label}: column '{column}' stamps its rows in whole {unit}, coarser than its clock: the rows are "
                f"spread evenly, every {period:.6g} s, each within its stamp (a row missed within a stamp would not "
                "show)"
            )
    return time, None


__all__ = ["spread_within_stamps"]
