"""Checks of a model file's ``training`` section: the expected next-run error a fit recorded."""

from __future__ import annotations

import math
from typing import Any, Mapping


def is_number(value: Any) -> bool:
    """A finite int or float (not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def expectation_problem(training: Mapping[str, Any]) -> str | None:
    """The next-run expectation under ``training``: a number ≥ 0, its range [low, high] around it, a method."""
    if "expected_next_run_rms_um" not in training:
        return None
    value = training["expected_next_run_rms_um"]
    if not is_number(value) or value < 0:
        return f"training.expected_next_run_rms_um = {value!r}: must be a finite number ≥ 0"
    bounds = training.get("expected_next_run_range_um")
    if (
        not isinstance(bounds, list)
        or len(bounds) != 2
        or not all(is_number(b) for b in bounds)
        or not bounds[0] <= value <= bounds[1]
    ):
        return f"training.expected_next_run_range_um = {bounds!r}: must be [low, high] with low <= expected <= high"
    if not isinstance(training.get("expected_next_run_method"), str):
        return "training.expected_next_run_method must say how the expectation was estimated"
    return None
