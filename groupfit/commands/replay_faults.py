"""Which readings put the run-time rule on held readings or into sensor fault during a replay, and why.

A reading outside its valid range (``switching.temp_min_c`` … ``temp_max_c``, a derived input's source range)
is held, then a sensor fault: those samples are not scored. A run whose readings are in another unit than the
modelling run's (°F under a °C name, r/s for r/min) faults on most samples and would otherwise be scored on
the few left, with nothing to say why. The readings are described by :mod:`groupfit.rule_faults`, which
``compare`` and ``diagnose`` share for their validation runs.
"""

from __future__ import annotations

from typing import Any

from groupfit.rule_faults import fault_readings

MOSTLY_UNSCORED = 0.5
"""A run with fewer scored samples than this share of its measured ones is not placed against the expected
next-run error: what is left is not the run."""


def mostly_unscored(data: dict[str, Any]) -> bool:
    """Whether fewer than :data:`MOSTLY_UNSCORED` of the run's measured samples were scored."""
    measured = data.get("measured_samples") or 0
    return measured > 0 and data.get("scored_samples", measured) < MOSTLY_UNSCORED * measured


__all__ = ["MOSTLY_UNSCORED", "fault_readings", "mostly_unscored"]
