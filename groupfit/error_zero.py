"""A next run whose thermal error is measured from another zero than the modelling run's.

A probe's trigger position logged as it is (a 3-D printer's ``mcu_pos_z`` after
a re-homing), a displacement sensor re-mounted between two days: the error of
the next run then differs from the modelling run's by a constant far larger
than any thermal drift, and the compensation's residual is that constant. The
RMS a replay reports without checks stays what the log says (probe checks may
take the constant up, or their gate may reject it as a bad reading);
:func:`zero_offset` adds a note that names the constant and what to do: read
each run's error from its first reading, ``--error 'COLUMN-start'``
(:mod:`groupfit.error_start`).

A constant residual has another common cause, named first when the run shows
it: the machine as a whole at another level than on the modelling run (a warm
start, a day at another air level), every input read above (or below) its
modelling range over the whole run. The model then reads a level it never saw
through coefficients fitted without it, and misses by a near constant too
(:func:`level_shift`).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

SPREAD_RATIO = 5.0
"""The residual's mean is a constant offset when it exceeds its spread (standard deviation) this many times."""
EXPECTED_RATIO = 10.0
"""… and this many times the model file's expected next-run RMS."""


def level_shift(beyond: Sequence[dict[str, Any]], n_inputs: int) -> tuple[str, list[dict[str, Any]]] | None:
    """``("above" | "below", entries)`` when the inputs of ``beyond_modelling_range`` (the reference's entry left
    aside) that lie beyond their span over the whole run all lie on one side, and they are at least two and at
    least half of the model's ``n_inputs`` inputs, with no input wholly on the other side; None otherwise."""
    inputs = [b for b in beyond if not b.get("reference")]
    above = [b for b in inputs if b["run"][0] > b["span"][1]]
    below = [b for b in inputs if b["run"][1] < b["span"][0]]
    side, entries = ("above", above) if len(above) >= len(below) else ("below", below)
    if (above and below) or len(entries) < max(2, math.ceil(n_inputs / 2)):
        return None
    return side, entries


def zero_offset(
    residual: np.ndarray | None,
    expected_rms_um: float | None,
    moved_reference: dict | None = None,
    shifted: tuple[str, list[dict[str, Any]]] | None = None,
) -> tuple[dict, list[str]]:
    """``{"constant_offset_um": m}`` and a note when the replay's residual (without probe checks) is nearly a
    constant far beyond what the model expected of a next run; nothing otherwise. ``moved_reference``: the
    reference column's entry of ``beyond_modelling_range`` when the run left its span (another cause the note
    names first: a day warmer or colder than the modelling day, under a model that takes its inputs against it).
    ``shifted``: :func:`level_shift` of the run (the machine as a whole at another level, named first too)."""
    if residual is None or not isinstance(expected_rms_um, (int, float)) or not expected_rms_um > 0:
        return {}, []
    scored = residual[np.isfinite(residual)]
    if scored.size < 3:
        return {}, []
    mean, spread = float(np.mean(scored)), float(np.std(scored))
    if not (abs(mean) > SPREAD_RATIO * spread and abs(mean) > EXPECTED_RATIO * expected_rms_um):
        return {}, []
    times = abs(mean) / expected_rms_um
    head = f"the residual is nearly a constant {mean:.4g} µm (its spread {spread:.3g} µm), {times:.0f}× the expected "
    zero_fix = "read both runs' error from their first readings (fit with --error 'COLUMN-start') and refit"
    zero = (
        "this run's error seems measured from another zero than the modelling run's (a probe's position after "
        f"re-homing, a sensor re-mounted); {zero_fix}"
    )
    note = head + "next-run RMS: " + zero
    if moved_reference is not None:
        name, (low, high), (first, last) = moved_reference["input"], moved_reference["span"], moved_reference["run"]
        note = (
            f"{head}next-run RMS, while the reference {name} the inputs are taken against reads "
            f"{first:.4g}..{last:.4g} (modelled {low:.4g}..{high:.4g}): if the error follows the parts' own "
            f"temperatures rather than their difference to {name}, a day at another {name} is off by about the "
            "whole change; refit with "
            f"--reference none (or on runs of several {name} levels). Else {zero}"
        )
    elif shifted is not None:
        side, entries = shifted
        gap = min(b["run"][0] - b["span"][1] if side == "above" else b["span"][0] - b["run"][1] for b in entries)
        names = ", ".join(b["input"] for b in entries)
        note = (
            f"{head}next-run RMS, while {names} read {side} their modelling ranges over the whole run (by at "
            f"least {gap:.2g}): the machine as a whole {'warmer' if side == 'above' else 'cooler'} than on the "
            "modelling run (a warm start, a day at another air level), a level the model never saw and reads "
            "through coefficients fitted without it; record a run that starts in such a state and fit on both "
            "(--data A B). If the error was measured from another zero instead (a probe's position after "
            f"re-homing, a sensor re-mounted), {zero_fix}"
        )
    return {"constant_offset_um": mean}, [note]


__all__ = ["EXPECTED_RATIO", "SPREAD_RATIO", "level_shift", "zero_offset"]
