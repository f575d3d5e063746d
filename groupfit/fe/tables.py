"""The scenario tables' reading helpers, shared by every scenario kind (headstock, rod, ball screw).

Every key is read through :class:`ScenarioTable`; a wrong value raises
:class:`groupfit.errors.InputError` with the key's dotted name.
"""

from __future__ import annotations

import dataclasses
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


NUMBER_KEYS = {
    "length": ("length_m", "positive"),
    "width": ("width_m", "positive"),
    "height": ("height_m", "positive"),
    "axis_height": ("axis_height_m", "positive"),
    "bore_diameter": ("bore_diameter_m", "positive"),
    "radius": ("radius_m", "positive"),
    "diameter": ("diameter_m", "positive"),
    "lead": ("lead_m", "positive"),
    "density": ("density_kg_m3", "positive"),
    "heat_capacity": ("heat_capacity_J_kgK", "positive"),
    "conductivity": ("conductivity_W_mK", "positive"),
    "expansion": ("expansion_1_K", "nonnegative"),
    "poisson": ("poisson", "nonnegative"),
    "young": ("young_Pa", "positive"),
    "convection": ("convection_W_m2K", "nonnegative"),
    "bore_convection": ("bore_convection_W_m2K", "nonnegative"),
    "mount_conductance": ("mount_conductance_W_m2K", "positive"),
    "front_W": ("front_heat_W", "nonnegative"),
    "rear_W": ("rear_heat_W", "nonnegative"),
    "reference_speed_rpm": ("reference_speed_rpm", "positive"),
    "speed_exponent": ("speed_exponent", "nonnegative"),
}
"""The scenarios' physical numbers: field of their dataclass → (key in the scenario table, the sign it must have)."""


def read_numbers(table: ScenarioTable, defaults, fields: tuple[str, ...] | None = None) -> dict[str, float]:
    """The numbers ``fields`` of the dataclass ``defaults`` (all its fields when None), in that order, each
    read from its key of :data:`NUMBER_KEYS` (the field of ``defaults`` when the key is absent)."""
    if fields is None:
        fields = tuple(field.name for field in dataclasses.fields(defaults))
    values = {}
    for name in fields:
        key, sign = NUMBER_KEYS[name]
        values[name] = table.number(key, getattr(defaults, name), **{sign: True})
    return values


def read_number_section(top: ScenarioTable, name: str, defaults):
    """The dataclass ``defaults`` with every field read from the table ``[name]`` (:func:`read_numbers`)."""
    table = top.sub(name)
    values = read_numbers(table, defaults)
    table.finish()
    return type(defaults)(**values)


def read_sensors(raw, default: dict, *, layout: str, reserved, position) -> dict:
    """The ``[sensors]`` table, NAME = its position (``default`` when absent).

    ``layout`` says in the message what a position is; ``reserved(name)``: the
    name is another column's; ``position(key, value)`` checks one position
    (``key``: its dotted name) and returns it.
    """
    if raw is None:
        return dict(default)
    if not isinstance(raw, dict) or not raw:
        raise fail("sensors", f"must be a table of NAME = {layout}")
    sensors = {}
    for name, value in raw.items():
        key = f"sensors.{name}" if name.strip() else f"sensors.{name!r}"
        if not name.strip() or name != name.strip() or "," in name:
            raise fail(key, "a sensor needs a name, without a comma or spaces around it, to head its column")
        if reserved(name):
            raise fail(key, "this name is reserved for another column; rename the sensor")
        sensors[name] = position(key, value)
    return sensors
