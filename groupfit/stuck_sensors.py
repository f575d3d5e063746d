"""A sensor that reads one value unchanged over a long stretch while the machine around it moves: stuck, or
disconnected with its last value held by the logger.

A thermally coupled sensor read to a fine step does not hold its value exactly for hours while the other
sensors move by a large part of their range: its own noise alone moves it. A model fitted on such a
stretch learns a weight from readings that do not say what the part did, so loading says so (a note; the
rows are kept as read, since only the user knows whether the part was truly still).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

MIN_SHARE = 0.1
"""A stretch shorter than this share of the run's rows is not named."""
MIN_ROWS = 20
"""Nor one of fewer rows."""
MIN_STEPS = 20
"""A sensor whose whole range spans fewer steps of its resolution may rest on one value: never named."""
OTHERS_MOVE = 0.2
"""The other inputs move, during the stretch, by at least this share of their range over the run (median)."""


def longest_unchanged(values: np.ndarray) -> tuple[int, int]:
    """First and last row (0-based) of the longest stretch of consecutive equal readings; NaN ends a stretch."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return 0, -1
    same = np.r_[False, (values[1:] == values[:-1])]
    starts = np.flatnonzero(~same)
    ends = np.r_[starts[1:] - 1, len(values) - 1]
    k = int(np.argmax(ends - starts))
    return int(starts[k]), int(ends[k])


def resolution(values: np.ndarray) -> float:
    """The smallest step between two different consecutive readings (the sensor's resolution as logged)."""
    steps = np.abs(np.diff(values[np.isfinite(values)]))
    steps = steps[steps > 0]
    return float(steps.min()) if steps.size else 0.0


def spans(readings: np.ndarray) -> np.ndarray:
    """Each column's range over its finite readings (0 for a column without any)."""
    finite = np.isfinite(readings)
    high = np.where(finite, readings, -np.inf).max(axis=0)
    low = np.where(finite, readings, np.inf).min(axis=0)
    return np.where(finite.any(axis=0), high - low, 0.0)


def stuck_stretches(readings: np.ndarray, names: Sequence[str]) -> list[tuple[str, int, int, float]]:
    """The inputs that read one value over a long stretch while the others move: ``(name, first, last, share)``
    with rows 0-based and ``share`` the others' median move during it (share of their range)."""
    readings = np.asarray(readings, dtype=float)
    n_rows, n_inputs = readings.shape
    if n_inputs < 2 or n_rows < MIN_ROWS:
        return []
    ranges = spans(readings)
    found = []
    for j, name in enumerate(names):
        first, last = longest_unchanged(readings[:, j])
        rows = last - first + 1
        step = resolution(readings[:, j])
        if rows < max(MIN_ROWS, MIN_SHARE * n_rows) or not step > 0 or ranges[j] < MIN_STEPS * step:
            continue
        others = [k for k in range(n_inputs) if k != j and ranges[k] > 0]
        if not others:
            continue
        stretch = readings[first : last + 1][:, others]
        moved = spans(stretch) / ranges[others]
        share = float(np.median(moved))
        if share >= OTHERS_MOVE:
            found.append((name, first, last, share))
    return found


def stuck_sensor_notes(readings: np.ndarray, names: Sequence[str], time_s: np.ndarray, label: str) -> tuple[str, ...]:
    """A note per input :func:`stuck_stretches` finds (rows 1-based as in the file's data rows), or none."""
    notes = []
    n_rows = len(readings)
    for name, first, last, share in stuck_stretches(readings, names):
        value = float(readings[first, list(names).index(name)])
        hours = (float(time_s[last]) - float(time_s[first])) / 3600.0
        notes.append(
            f"{label}: '{name}' reads {value:.6g} unchanged on rows {first + 1}-{last + 1} ({hours:.3g} h, "
            f"{100 * (last - first + 1) / n_rows:.0f} % of the run) while the other inputs move by "
            f"{100 * share:.0f} % of their range (median): a stuck or disconnected sensor? Those rows are used as "
            "read (a model fitted on them learns from them; --temps leaves a sensor out)"
        )
    return tuple(notes)


__all__ = ["longest_unchanged", "resolution", "spans", "stuck_sensor_notes", "stuck_stretches"]
