"""Which readings put the run-time rule on held readings or into sensor fault during a replay, and why.

A reading outside its valid range (``switching.temp_min_c`` … ``temp_max_c``, a derived input's source range)
is held, then a sensor fault: those samples are not scored. A run whose readings are in another unit than the
modelling run's (°F under a °C name, r/s for r/min) faults on most samples and would otherwise be scored on
the few left, with nothing to say why.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from groupfit.runtime import FAULT_HELD, FAULT_SENSOR

MOSTLY_UNSCORED = 0.5
"""A run with fewer scored samples than this share of its measured ones is not placed against the expected
next-run error: what is left is not the run."""


def fault_readings(tables, readings: np.ndarray, fault: np.ndarray) -> tuple[dict[str, Any], list[str]]:
    """Per reading outside its valid range on some sample: its name, valid range, the samples and the values
    seen there; and a note (none when the rule never held a reading)."""
    if not np.any((fault & (FAULT_SENSOR | FAULT_HELD)) != 0):
        return {}, []
    found = []
    for r, name in enumerate(tables.raw_names):
        low, high = float(tables.valid_min[r]), float(tables.valid_max[r])
        values = np.asarray(readings[:, r], dtype=float)
        bad = ~((values >= low) & (values <= high))
        if not bad.any():
            continue
        seen = values[bad & np.isfinite(values)]
        found.append(
            {
                "reading": str(name),
                "valid": [low, high],
                "samples": int(bad.sum()),
                "not_a_number": int(np.sum(~np.isfinite(values[bad]))),
                "seen": [float(seen.min()), float(seen.max())] if seen.size else None,
            }
        )
    if not found:
        return {}, []
    parts = []
    for f in found:
        kinds = []
        if f["seen"]:
            beyond = f["samples"] - f["not_a_number"]
            kinds.append(f"{f['seen'][0]:.4g}..{f['seen'][1]:.4g} on {beyond} sample(s)")
        if f["not_a_number"]:
            kinds.append(f"not finite (NaN or ±inf) on {f['not_a_number']} sample(s)")
        parts.append(f"{f['reading']} {' and '.join(kinds)} (valid {f['valid'][0]:g}..{f['valid'][1]:g})")
    n = len(readings)
    whole = [f["reading"] for f in found if f["samples"] - f["not_a_number"] > n // 2]
    hint = (
        f"; {', '.join(whole)} beyond its range on most samples: logged in another unit than the modelling run "
        "(°F for °C, r/s for r/min)? convert it as that run was logged"
        if whole
        else ""
    )
    note = (
        "readings outside their valid range (held, then a sensor fault; those samples are not scored): "
        + "; ".join(parts)
        + hint
    )
    return {"readings_out_of_range": found}, [note]


def mostly_unscored(data: dict[str, Any]) -> bool:
    """Whether fewer than :data:`MOSTLY_UNSCORED` of the run's measured samples were scored."""
    measured = data.get("measured_samples") or 0
    return measured > 0 and data.get("scored_samples", measured) < MOSTLY_UNSCORED * measured


__all__ = ["MOSTLY_UNSCORED", "fault_readings", "mostly_unscored"]
