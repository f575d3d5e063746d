"""The unit a controller passes a reading in, and what to convert where the modelling log wrote another.

groupfit reads a log's temperatures in °C whatever unit their names give (``T1 [°F]``, ``T1 [0.1°C]``, kelvin,
:mod:`groupfit.units_row`), and a position in mm (``probe_x_m``, :mod:`groupfit.position`): the model, its
valid ranges and its exported routines work in those units, so a controller that reads the sensor as the log
did must convert it first.
"""

from __future__ import annotations

from groupfit.default_columns import default_temperature_columns
from groupfit.units_row import CELSIUS_BY_UNIT, SHOWN, named_temperature_unit, temperature_factor

TEMPERATURE_UNIT = "degC"


def is_temperature_reading(tables, r: int) -> bool:
    """Whether reading ``r`` is a temperature: a measured input, the reference, or a column named as one."""
    name = tables.raw_names[r]
    return (
        tables.valid_origin[r] == "temperature"
        or r == getattr(tables, "reference_reading", -1)
        or bool(default_temperature_columns([name]))
        or named_temperature_unit(name) is not None
    )


def conversion_note(name: str) -> str | None:
    """What to convert a temperature reading from, when its modelling column's name gives another unit than °C
    (None when it gives none or °C)."""
    factored = temperature_factor(name)
    if factored is not None:
        return f"logged in {_ascii(factored.shown)}: pass it in degC"
    unit = named_temperature_unit(name)
    if unit is None or CELSIUS_BY_UNIT[unit] == (1.0, 0.0):
        return None
    scale, offset = CELSIUS_BY_UNIT[unit]
    formula = (
        f"degC = x * {scale!r} {'-' if offset < 0 else '+'} {abs(offset)!r}" if offset else f"degC = x * {scale!r}"
    )
    return f"logged in {_ascii(SHOWN.get(unit, unit))}: pass it in degC ({formula}, as groupfit converts it)"


def _ascii(unit: str) -> str:
    """A unit as the generated comments write it (``degF`` for ``°F``)."""
    return unit.replace("°", "deg").replace("º", "deg")


__all__ = ["TEMPERATURE_UNIT", "conversion_note", "is_temperature_reading"]
