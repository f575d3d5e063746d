"""The levels of an operating setting (a spindle speed, a heater on/off), also when it is read back with noise.

A setting is piecewise constant with few levels and moves in steps; a
measurement creeps. A drive that reports its speed back logs 2498…2502 r/min
for a set 2500: such a column is read by its levels (the median of each group
of readings), so that the conditions it marks, the folds cut at its changes
and the heat levels of an AR(1) model are the ones that were set.
"""

from __future__ import annotations

import numpy as np

MAX_LEVELS = 64
"""An operating column takes at most this many distinct values (a speed spectrum has dozens)…"""
MAX_CHANGE_FRACTION = 0.05
"""…changes value on at most this share of its samples (a level is held for at least 20 samples on average)…"""
FEW_LEVELS = 8
MAX_FEW_LEVEL_CHANGE_FRACTION = 0.25
"""…or, with at most ``FEW_LEVELS`` values (an on/off signal, a speed programme), on at most this share: such
a column read on the rows of a probe cycle only (an error measured every few samples) is still a setting…"""
MIN_STEP_FRACTION = 0.05
"""…and moves in steps: its median change is at least this share of its range. A setting jumps from one
level to another; a quantised measurement (an ambient read to 0.1 K) creeps by one quantum."""
LEVEL_GAP_FRACTION = 0.05
"""A setting read back with noise (a spindle speed logged as 2498…2502 r/min) is read as its levels when its
sorted readings fall into groups this share of the range apart…"""
LEVEL_SPREAD_FRACTION = 0.02
"""…each group within this share of the range (the noise); a drifting signal has no such groups. Readings on a
ramp between levels (a drive accelerating over several samples) are left out of the groups and read as the
level the ramp reaches…"""
MIN_STEADY_SHARE = 0.5
"""…as long as most readings are steady (within that share of a neighbour)."""
MAX_MISSED_FRACTION = 0.05
"""A setting with at most this share of its readings missed (an empty cell, a ``---``) is read with each
missed one held at the reading before it (:func:`held_setting`): a setting holds until it is changed."""


def is_setting(values: np.ndarray) -> bool:
    """Whether a column looks like an operating setting, as logged or read by its levels."""
    values = np.asarray(values, dtype=float)
    return _piecewise_constant(values) or _piecewise_constant(_levels(values))


def setting_levels(values: np.ndarray) -> np.ndarray:
    """The values of an operating column as the setting's levels: the column itself when it is piecewise
    constant, else (a setting read back with noise) each reading replaced by its level, the median of a group
    of steady readings (:data:`LEVEL_GAP_FRACTION`), when they fall into such groups; else the column itself."""
    values = np.asarray(values, dtype=float)
    if _piecewise_constant(values):
        return values
    levels = _levels(values)
    return levels if _piecewise_constant(levels) else values


def held_setting(values: np.ndarray) -> np.ndarray | None:
    """The readings of a column with each missed one (not finite) held at the reading before it (the first ones
    at the first reading); None when more than :data:`MAX_MISSED_FRACTION` of them, or all, are missed."""
    values = np.asarray(values, dtype=float)
    read = np.isfinite(values)
    if read.all():
        return values
    if not read.any() or np.count_nonzero(~read) > MAX_MISSED_FRACTION * values.size:
        return None
    last = np.maximum.accumulate(np.where(read, np.arange(values.size), -1))
    return values[np.where(last >= 0, last, np.flatnonzero(read)[0])]


def _piecewise_constant(values: np.ndarray | None) -> bool:
    if values is None or not np.isfinite(values).all():
        return False
    if np.ptp(values) == 0.0:  # a source on from the start at its set-point: it heats from rest
        return True
    steps = np.abs(np.diff(values))
    steps = steps[steps > 0]
    levels = len(np.unique(values))
    changes = MAX_CHANGE_FRACTION if levels > FEW_LEVELS else MAX_FEW_LEVEL_CHANGE_FRACTION
    return bool(
        levels <= MAX_LEVELS
        and len(steps) <= changes * len(values)
        and np.median(steps) >= MIN_STEP_FRACTION * np.ptp(values)
    )


def _levels(values: np.ndarray) -> np.ndarray | None:
    """Each steady reading as its nearest level, the levels being the medians of the groups of steady readings
    (see :data:`LEVEL_GAP_FRACTION`), and a reading on a ramp as the level it reaches; None when the steady
    readings fall into no such groups."""
    span = float(np.ptp(values)) if values.size > 1 and np.isfinite(values).all() else 0.0
    if span == 0.0:
        return None
    steady = _steady(values, LEVEL_SPREAD_FRACTION * span)
    if np.count_nonzero(steady) < MIN_STEADY_SHARE * values.size:
        return None
    ordered = np.sort(values[steady])
    cuts = np.flatnonzero(np.diff(ordered) > LEVEL_GAP_FRACTION * span)
    if not cuts.size or cuts.size >= MAX_LEVELS:
        return None
    medians = []
    for members in np.split(ordered, cuts + 1):
        if np.ptp(members) > LEVEL_SPREAD_FRACTION * span:
            return None
        medians.append(float(np.median(members)))
    levels = np.asarray(medians)
    nearest = levels[np.argmin(np.abs(values[:, None] - levels[None, :]), axis=1)]
    return _reached(nearest, steady)


def _reached(levels: np.ndarray, steady: np.ndarray) -> np.ndarray:
    """Readings on a ramp take the level the ramp reaches (the next steady reading's; the last one's at the
    end): the setting changed when the ramp began, and a ramp passing a level is not a stay there."""
    index = np.flatnonzero(steady)
    following = np.searchsorted(index, np.arange(len(levels)))
    return levels[index[np.minimum(following, len(index) - 1)]]


def _steady(values: np.ndarray, tolerance: float) -> np.ndarray:
    """Readings within ``tolerance`` of a neighbour: not on a ramp between levels (the last reading before a
    step and the first after it are each close to the other side's neighbour)."""
    close = np.abs(np.diff(values)) <= tolerance
    return np.r_[False, close] | np.r_[close, False]


__all__ = ["MAX_MISSED_FRACTION", "held_setting", "is_setting", "setting_levels"]
