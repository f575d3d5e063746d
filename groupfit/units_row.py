"""A logger's row of units under the header: the columns it gives in mm, nm, minutes, °F or K read in µm, s, °C.

Many loggers write the units in a row of their own under the names (``Time,CH1,CH8`` over ``s,degC,mm``)
instead of in the names (``error_mm``), or in every cell (``20.5 °C``). :mod:`groupfit.textlayout` leaves such
rows out of the data, and the units out of the cells, and keeps them; here the row that names the most units
(and the units of the cells) is read, and

* a column in another unit of length than µm, of time than s (the time column), or of temperature than °C is
  converted in place, with a note, when its name gives no unit; a name and a units row that disagree are
  refused, naming both;
* the columns in a unit of length are the candidates for the thermal error when the log has no column named
  as one (``CH8`` over ``um``).
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from groupfit.default_columns import (
    MICROMETRES_PER_UNIT,
    default_temperature_columns,
    error_like_columns,
    named_length_unit,
)
from groupfit.errors import InputError
from groupfit.timestamps import UNIT_SECONDS, named_time_unit
from groupfit.unit_factors import FactoredUnit, factored_unit

FAHRENHEIT = ("°f", "ºf", "degf", "deg f", "deg.f", "deg. f", "℉", "fahrenheit", "f")
KELVIN = ("k", "°k", "ºk", "kelvin")
CELSIUS_BY_UNIT = {
    **dict.fromkeys(("°c", "ºc", "degc", "deg c", "deg.c", "deg. c", "℃", "celsius", "c"), (1.0, 0.0)),
    **dict.fromkeys(KELVIN, (1.0, -273.15)),
    **dict.fromkeys(FAHRENHEIT, (5.0 / 9.0, -32.0 * 5.0 / 9.0)),
}
"""Units of temperature a units row may give, and their (scale, offset) to °C."""
SHOWN = {
    **dict.fromkeys(FAHRENHEIT, "°F"),
    **dict.fromkeys(KELVIN, "K"),
}
"""How a unit of temperature is named in a note."""
BRACKETS = re.compile(r"^[\[(（［]\s*(.*?)\s*[\])）］]$")
NAMED_TEMPERATURE_UNIT = re.compile(
    r"([°º]\s*[CFK](?![a-z])|(?<![a-z])deg\.?\s*[CF](?![a-z])|℃|℉|fahrenheit|kelvin|[\[(（［]\s*[°º]?[CFK]\s*[\])）］])",
    re.IGNORECASE,
)
"""A unit of temperature in a column's name (``T1 [°F]``, ``Temp, °F (LGR S/N: 2001)``, ``bed_degF``, ``T1 (K)``,
``T1 (F)``, ``T1 (deg. F)``, ``T1 [ºF]`` with the ordinal sign many keyboards give for the degree)."""


def unit_of(cell: str) -> tuple[str, str] | None:
    """``(kind, unit)`` of a units-row cell (kind ``"length"``, ``"time"`` or ``"temperature"``), None when it
    gives no unit groupfit converts (``rpm``, ``%``, a description)."""
    text = str(cell).strip()
    bracketed = BRACKETS.match(text)
    unit = (bracketed.group(1) if bracketed else text).strip().rstrip(".").lower()
    if unit in MICROMETRES_PER_UNIT:
        return "length", unit
    if unit in UNIT_SECONDS:
        return "time", unit
    if unit in CELSIUS_BY_UNIT:
        return "temperature", unit
    return None


def row_units(frame: pd.DataFrame, time: str | None, label: str) -> tuple[dict[str, tuple[str, str]], str | None]:
    """The units of the frame's columns by the text row under its header that names the most, and by the
    units written in their cells (``20.5 °C``; empty: none); and the note when the units row was read as the
    units of the last columns (:func:`aligned_row_units`)."""
    rows = frame.attrs.get("text_rows") or []
    columns = [str(column) for column in frame.columns]
    found = [aligned_row_units(row, columns, time, label) for row in rows]
    units, note = max(found, key=lambda pair: len(pair[0]), default=({}, None))
    in_cells = {column: unit for column, cell in frame.attrs.get("cell_units", {}).items() if (unit := unit_of(cell))}
    return {**units, **in_cells}, note


def aligned_row_units(
    row: dict[str, str], columns: list[str], time: str | None, label: str
) -> tuple[dict[str, tuple[str, str]], str | None]:
    """The units a text row under the header gives its columns, and a note when it was realigned.

    A row split at spaces with fewer cells than columns is placed from the left (``°F °F µm`` under ``time_s
    T1 T2 error_um``), which puts a unit of temperature or length over the time column and shifts every other
    unit one column off: °F converted on the time, µm on a temperature, the error left in mm. Such a row is
    read as the units of the last columns when that puts no unit of temperature or length over the time, no
    temperature over a column named as the error and no length over one named as a sensor; otherwise it is
    refused, naming the unit and the column.
    """
    units = {column: unit for column, cell in row.items() if (unit := unit_of(cell))}
    if time is None or _time_fits(units, time):
        return units, None
    cells = list(row.values())
    if len(cells) < len(columns):
        last = columns[len(columns) - len(cells) :]
        moved = {column: unit for column, cell in zip(last, cells) if (unit := unit_of(cell))}
        if _time_fits(moved, time) and not _against_names(moved, columns):
            return moved, (
                f"{label}: the row of units under the header gives {len(cells)} units for {len(columns)} columns "
                f"({' '.join(cells)}): read as the units of the last {len(cells)}, from '{last[0]}' on (placed from "
                f"the first, '{row[time]}' would stand over the time column '{time}')"
            )
    raise InputError(
        f"{label}: the row of units under the header puts '{row[time]}', a unit of {units[time][0]}, over the time "
        f"column '{time}' ({len(cells)} units for {len(columns)} columns); write one unit per column, '-' for a "
        "column without one"
    )


def named_temperature_unit(name: str) -> str | None:
    """The unit of temperature a column's name gives (a key of :data:`CELSIUS_BY_UNIT`), None when none."""
    found = NAMED_TEMPERATURE_UNIT.search(str(name))
    unit = unit_of(found.group(1).replace(" ", "")) if found else None
    return unit[1] if unit and unit[0] == "temperature" else None


def temperature_factor(name: object) -> FactoredUnit | None:
    """The factor of a unit of temperature a name gives with one (``T1 [0.1°C]``, ``T1 [°C/10]``), else None."""
    factored = factored_unit(name)
    unit = unit_of(factored.unit.replace(" ", "")) if factored is not None else None
    return factored if unit is not None and unit[0] == "temperature" else None


def _time_fits(units: dict[str, tuple[str, str]], time: str) -> bool:
    """Whether ``units`` give the time column a unit of time or none."""
    return units.get(time, ("time",))[0] == "time"


def _against_names(units: dict[str, tuple[str, str]], columns: list[str]) -> bool:
    """Whether ``units`` put a unit of temperature over a column named as the thermal error, or a unit of
    length over one named as a temperature sensor (a row two units short, placed from either end)."""
    errors = set(error_like_columns(columns))
    sensors = set(default_temperature_columns(columns)) - errors
    return any(
        (kind == "temperature" and column in errors) or (kind == "length" and column in sensors)
        for column, (kind, _) in units.items()
    )


def read_in_row_units(frame: pd.DataFrame, time: str, label: str) -> tuple[list[str], tuple[str, ...]]:
    """Convert, in place, the columns the units row gives in other units (see the module docstring).

    Returns
    -------
    lengths, notes
        The columns in a unit of length (in table order), and the notes naming the conversions.

    Raises
    ------
    InputError
        A column whose name and units row give different units.
    """
    units, aligned = row_units(frame, time, label)
    lengths, converted = [], []
    for column in frame.columns:
        factored = temperature_factor(column)
        if factored is not None and pd.api.types.is_numeric_dtype(frame[column]):
            frame[column] = frame[column].to_numpy(dtype=float) * factored.factor
            converted.append(f"'{column}' ×{factored.factor:g} (in {factored.shown})")
        named = named_temperature_unit(str(column))
        kind, unit = units.get(str(column), ("temperature", named) if named else (None, None))
        if kind is None or not pd.api.types.is_numeric_dtype(frame[column]):
            continue
        if kind == "length":
            lengths.append(str(column))
        scale, offset = _to_base(column, kind, unit, time, label)
        if unit in KELVIN and not _absolute_kelvin(frame[column]):
            continue  # readings of a few kelvin: a temperature difference (over a reference), kept as logged
        if (scale, offset) != (1.0, 0.0):
            frame[column] = frame[column].to_numpy(dtype=float) * scale + offset
            converted.append(f"'{column}' from {SHOWN.get(unit, unit)}")
    notes = (aligned,) if aligned else ()
    if converted:
        notes += (
            f"{label}: converted to µm, s and °C from the units of their names, cells or the row under the header: "
            + ", ".join(converted),
        )
    return lengths, notes


COLDEST_KELVIN = 173.15
"""Readings in K all above this (−100 °C) are absolute temperatures; one below it makes the column a temperature
difference in K (the German convention, ``ΔT [K]``), which is read as logged."""


def _absolute_kelvin(values: pd.Series) -> bool:
    finite = values.to_numpy(dtype=float)
    finite = finite[np.isfinite(finite)]
    return bool(finite.size) and float(finite.min()) > COLDEST_KELVIN


def _to_base(column, kind: str, unit: str, time: str, label: str) -> tuple[float, float]:
    """(scale, offset) that take a column from its row unit to µm, s or °C; (1, 0) when its name gives the unit."""
    if kind == "length":
        named, scale = named_length_unit(str(column)), MICROMETRES_PER_UNIT[unit]
        named_scale = MICROMETRES_PER_UNIT.get(named) if named else None
        offset = 0.0
    elif kind == "time":
        if str(column) != time:
            return 1.0, 0.0
        named, scale, offset = named_time_unit(str(column)), UNIT_SECONDS[unit], 0.0
        named_scale = UNIT_SECONDS.get(named) if named else None
    else:
        named = named_temperature_unit(str(column))
        named_scale = CELSIUS_BY_UNIT[named] if named else None
        scale, offset = CELSIUS_BY_UNIT[unit]
        if named_scale is not None and named_scale != (scale, offset):
            raise InputError(
                f"{label}: column '{column}' is named in {named} but its cells or the row of units under the "
                f"header give '{unit}'; correct the one that is wrong"
            )
        return scale, offset
    if named_scale is None:
        return scale, offset
    if not np.isclose(named_scale, scale):
        raise InputError(
            f"{label}: column '{column}' is named in {named} but the row of units under the header gives "
            f"'{unit}'; correct the one that is wrong"
        )
    return 1.0, 0.0  # the name's unit is read where the column is


__all__ = ["aligned_row_units", "read_in_row_units", "row_units", "temperature_factor", "unit_of"]
