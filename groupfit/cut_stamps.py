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
placed (a duplicated row, a gap, two recordings) is left to be refused.
"""

from __future__ import annotations

import numpy as np

from groupfit.timestamps import STAMP_RESOLUTIONS_S

SHARED_SHARE = 0.8
"""Least share of the rows that share their stamp with another row for the stamps to be taken as cut."""


def spread_within_stamps(time: np.ndarray, label: str, column: str) -> tuple[np.ndarray, str | None]:
    """The rows' times spread evenly within their cut stamps, and a note (``time`` and None: not cut stamps)."""
    time = np.asarray(time, dtype=float)
    steps = np.diff(time)
    if time.size < 3 or np.any(steps < 0):
        return time, None
    shared = np.r_[steps == 0, False] | np.r_[False, steps == 0]
    if shared.mean() < SHARED_SHARE:
        return time, None
    offsets = time - time[0]
    resolution = next(
        (r for r in STAMP_RESOLUTIONS_S if np.all(np.abs(offsets / r - np.round(offsets / r)) <= 1e-6)), None
    )
    if resolution is None:
        return time, None
    rows = np.arange(time.size, dtype=float)
    fitted = float(np.polyfit(rows, time + resolution / 2, 1)[0])
    for period in dict.fromkeys((*(round(fitted, digits) for digits in range(4)), fitted)):
        if period <= 0:
            continue
        lowest, highest = float(np.max(time - rows * period)), float(np.min(time + resolution - rows * period))
        if lowest < highest:
            start = (lowest + highest) / 2
            spread = start + rows * period
            unit = {60.0: "minutes", 1.0: "seconds"}.get(resolution, f"multiples of {resolution:g} s")
            return spread - spread[0], (
                f"{label}: column '{column}' stamps its rows in whole {unit}, about {resolution / period:.3g} under "
                f"each: the rows are spread evenly, every {period:.6g} s, each within its stamp"
            )
    return time, None


__all__ = ["spread_within_stamps"]
