"""Which probe-check intervals the modelling runs' held-out stretches say help, and a note when some did not.

A check corrects the compensation with the error measured at one moment. When
the error the model leaves changes faster than the checks come, a correction
held until the next check can cost more than it gains: the held-out
stretches of :mod:`groupfit.recalibration_tuning` show it as an RMS with
checks above the RMS without them (by more than :data:`WORSE_BY`). ``fit``
and ``diagnose`` note it beside the ``recal`` line, and ``replay
--probe-every`` when the longest held-out interval not beyond its own is one
of them.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

WORSE_BY = 0.05
"""Checks count as doing worse than none when their held-out RMS is above it by more than this share: the
tolerance the chosen filter is held to against the offset hold, so that a model at its noise floor is not
flagged for a difference its held-out data cannot resolve."""


def interval_advice(chosen: Mapping[str, Any] | None, every_s: float | None = None) -> str | None:
    """A note naming the check intervals that did worse than no checks on held-out data, or None.

    Parameters
    ----------
    chosen : mapping or None
        The recalibration section's ``chosen`` object (its intervals, the
        held-out RMS with the chosen filter and without checks per interval).
    every_s : float, optional
        The interval a replay checks at: a note only when the longest held-out
        interval not beyond it did worse than no checks.
    """
    table = _held_out_table(chosen)
    if table is None:
        return None
    rows = sorted(zip(*table))
    worse = [(t, c, u) for t, c, u in rows if _worse(c, u)]
    if not worse:
        return None
    if every_s is not None:
        nearest = [row for row in rows if row[0] <= every_s]
        if not nearest or not _worse(*nearest[-1][1:]):
            return None
    listed = "/".join(_minutes(t) for t, _, _ in worse)
    figures = f"{'/'.join(f'{c:.3g}' for _, c, _ in worse)} against {'/'.join(f'{u:.3g}' for _, _, u in worse)} µm"
    said = (
        f"checks every {listed} min did more than {100 * WORSE_BY:g} % worse than none on the held-out "
        f"stretches of the modelling runs ({figures} without checks)"
    )
    helped = [t for t, c, u in rows if not _worse(c, u)]
    if not helped:
        said += "; the model leaves little a check can correct, and checks may cost more than they gain"
    elif max(helped) < worse[0][0]:
        said += f"; check at least every {_minutes(max(helped))} min"
    asked = f"--probe-every {every_s:g} s: " if every_s is not None else ""
    return f"{asked}{said}"


def _worse(checked: float, unchecked: float) -> bool:
    return checked > (1.0 + WORSE_BY) * unchecked


def _held_out_table(chosen: Mapping[str, Any] | None) -> tuple[list, list, list] | None:
    if not isinstance(chosen, Mapping):
        return None
    columns = [chosen.get(key) for key in ("intervals_s", "rms_chosen_um", "rms_none_by_interval_um")]
    if not all(isinstance(c, (list, tuple)) and c for c in columns) or len({len(c) for c in columns}) != 1:
        return None
    try:
        values = [[float(v) for v in c] for c in columns]
    except (TypeError, ValueError):
        return None
    if not all(math.isfinite(v) for c in values for v in c):
        return None
    return values[0], values[1], values[2]


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:g}"


__all__ = ["WORSE_BY", "interval_advice"]
