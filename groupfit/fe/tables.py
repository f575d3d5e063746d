"""The scenario tables' reading helpers, shared by every scenario kind (headstock, rod, ball screw).

Every key is read through :class:`ScenarioTable`; a wrong value raises
:class:`groupfit.errors.InputError` with the key's dotted name.
"""

from __future__ import annotations

import math

from groupfit.errors import InputError
from groupfit.tomlconfig import Table

from .schedule import StepSchedule


def fail(key: str, what: str) -> InputError:
    return InputError(f"config key '{key}': {what}")


class ScenarioTable(Table):
    """A scenario table: an unknown key points to the shipped scenarios for the spelling."""

    def finish(self, hint: str | None = None) -> None:
        super().finish(hint or "check the spelling against configs/paper_cycle.toml or configs/rod_ar1.toml")


def step_schedule(table: ScenarioTable, key: str, default, *, value_check=None) -> StepSchedule | None:
    raw = table.get(key, default)
    if raw is None:
        return None
    name = table.key(key)
    if not isinstance(raw, (list, tuple)) or not raw:
        raise fail(name, "expected a non-empty list of [duration_s, value] pairs")
    steps = []
    for i, step in enumerate(raw):
        if (
            not isinstance(step, (list, tuple))
            or len(step) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in step)
        ):
            raise fail(name, f"step {i + 1} must be [duration_s, value], got {step!r}")
        duration, value = float(step[0]), float(step[1])
        if duration <= 0:
            raise fail(name, f"step {i + 1} has duration {step[0]!r}; durations must be positive (seconds)")
        if value_check is not None:
            problem = value_check(value)
            if problem:
                raise fail(name, f"step {i + 1}: {problem}")
        steps.append((duration, value))
    return StepSchedule(tuple(steps))


def check_alignment(schedule: StepSchedule, key: str, step_s: float):
    for duration, _ in schedule.steps:
        if abs(duration / step_s - round(duration / step_s)) > 1e-6:
            raise fail(
                key,
                f"duration {duration:g} s is not a multiple of the "
                f"time step {step_s:g} s (sampling_period_s / substeps)",
            )


def non_negative(value):
    return None if value >= 0 else f"value must not be negative, got {value:g}"


def on_off(value):
    return None if value in (0.0, 1.0) else f"value must be 0 (off) or 1 (on), got {value:g}"
