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
"""…each group within this share of the range (the noise); a ramp or a drifting signal has no such groups."""


def is_setting(values: np.ndarray) -> bool:
    """Whether a column looks like an operating setting, as logged or read by its levels."""
    values = np.asarray(values, dtype=float)
    return _piecewise_constant(values) or _piecewise_constant(_levels(values))


def setting_levels(values: np.ndarray) -> np.ndarray:
    """The values of an operating column as the setting's levels: the column itself when it is piecewise
    constant, else (a setting read back with noise) each reading replaced by the median of its level's group
    (:data:`LEVEL_GAP_FRACTION`), when the readings fall into such groups; else the column itself."""
    values = np.asarray(values, dtype=float)
    if _piecewise_constant(values):
        return values
    levels = _levels(values)
    return levels if _piecewise_constant(levels) else values


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
    """Each reading as the median of its group of sorted readings (see :data:`LEVEL_GAP_FRACTION`), or None."""
    span = float(np.ptp(values)) if values.size and np.isfinite(values).all() else 0.0
    if span == 0.0:
        return None
    ordered = np.sort(values)
    cuts = np.flatnonzero(np.diff(ordered) > LEVEL_GAP_FRACTION * span)
    if not cuts.size or cuts.size >= MAX_LEVELS:
        return None
    groups = np.searchsorted((ordered[cuts] + ordered[cuts + 1]) / 2.0, values)
    medians = np.empty(cuts.size + 1)
    for g, members in enumerate(np.split(ordered, cuts + 1)):
        if np.ptp(members) > LEVEL_SPREAD_FRACTION * span:
            return None
        medians[g] = np.median(members)
    return medians[groups]


__all__ = ["is_setting", "setting_levels"]
