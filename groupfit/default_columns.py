"""The time, thermal-error and input columns of a log that does not name them, found by their names.

A log written by a logger rarely has groupfit's default names (``time_s``,
``error_um``). When a verb is not told which columns to read (``--time``,
``--error``) and the default is absent, the column whose name marks it for
the role is taken, with a note naming it:

* the time: a name such as ``Timestamp``, ``Date/Time``, ``Time``, ``Zeit
  [min]``, ``elapsed_h`` or ``t_s`` (:func:`groupfit.timestamps.time_like_columns`);
  of several, the first whose values increase from most rows to the next (a
  ``Date`` column and a ``Time`` of day beside it are read as one stamp by
  :mod:`groupfit.date_time_columns`);
* the thermal error: the one column named as an error, a deviation, a
  displacement or a drift (of an axis: ``Z drift``), or in µm (``dZ_um``,
  ``Abweichung [µm]``); with
  several such columns (five probes) nothing is guessed and the refusal
  lists them;
* the inputs: the columns named like sensors (``T1``, ``t12_C``), else those
  named as temperatures (``Spindle [°C]``, ``Temp3``, ``Motor temp``, ``TC2``), the ambient
  left out (:func:`default_temperature_columns`); a log that names none, the columns whose
  readings look like temperatures (:func:`temperature_like_columns`), with a note.

A column asked for by name is never replaced.
"""

from __future__ import annotations

import re
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.columns import is_ambient_name, is_counter
from groupfit.error_start import logged_spec
from groupfit.errors import InputError
from groupfit.readtable import datetimes_to_seconds
from groupfit.setting_levels import is_setting
from groupfit.timestamps import time_like_columns
from groupfit.unit_factors import factored_unit

WIDE_PREFIX = "err_P"

DEFAULT_TIME = "time_s"
DEFAULT_ERROR = "error_um"
ERROR_NAME = re.compile(
    r"^\s*(?:[xyz][\s_-]?)?(?:thermal[\s_-]?)?(?:error|err|deviation|displacement|disp|drift|deformation|fehler|"
    r"abweichung|verlagerung|d[xyz]|delta[\s_-]?[xyz])(?=$|[^a-z])"
    r"|^\s*(?:[^\W\d_]{1,14}\s)?[^\W\d_]{0,8}?(?:误差|誤差|位移|变形|変形|变位|変位|偏移|漂移|伸长|伸び|"
    r"오차|변위|변형|смещени|погрешност|деформаци|перемещени|дрейф)",
    re.IGNORECASE,
)
SPEED_NAME = re.compile(r"rpm|speed|drehzahl|[ru]/min|1/min|min-1|min\^-1|转速|回転数|回転速度", re.IGNORECASE)
"""A name that marks a speed column (``spindle_rpm``, ``S1 speed``, ``Drehzahl [1/min]``)."""

TEMPERATURE_NAME = re.compile(
    r"°[CF]|℃|℉|温度|気温|온도|기온|температур|deg[\s_]?[CF]\b|[\[(（][CFK][\])）]|_C$|(?:^|[^a-z])temp(?:$|[^a-z]|erat)|^\s*TC[\s_]?\d",
    re.IGNORECASE,
)
"""A name that marks a temperature column (in °C, °F or K)."""
MICROMETRES_PER_UNIT = {
    **dict.fromkeys(("mm", "毫米", "мм"), 1000.0),
    **dict.fromkeys(("um", "µm", "μm", "micron", "microns", "微米", "мкм"), 1.0),
    **dict.fromkeys(("nm", "纳米"), 1e-3),
    **dict.fromkeys(("in", "inch", "inches"), 25400.0),
    **dict.fromkeys(("mil", "mils", "thou"), 25.4),
}
"""Length units a column's name may end in (``error_mm``, ``dZ [µm]``, ``drift (nm)``, ``dZ [in]``, ``dZ [mils]``),
in µm."""
LENGTH_UNIT = re.compile(
    r"(?:^|[\s_\[(/（［])(mm|um|µm|μm|microns?|nm|inch(?:es)?|in|mils?|thou|微米|毫米|纳米|мкм|мм)\s*[\])）］]?\s*$",
    re.IGNORECASE,
)


SCALED_NAME = re.compile(r"^(?P<column>.*\S)\s*\*\s*(?P<factor>[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*$")
"""A column read with a factor, as ``--error`` may name it: ``mcu_pos_z*2.5`` is column ``mcu_pos_z`` ×2.5 µm
per unit as logged (:mod:`groupfit.error_scale`)."""


def scaled_name(name: str | None) -> tuple[str, float] | None:
    """``(column, factor)`` of a name that asks for a column read with a factor (``z*2.5``, also
    ``z*2.5-start``, :mod:`groupfit.error_start`); None otherwise."""
    name = logged_spec(name) or name
    match = SCALED_NAME.match(str(name)) if name is not None else None
    return (match.group("column"), float(match.group("factor"))) if match else None


def length_unit(name: str | None) -> tuple[str, float]:
    """The length unit a column's name ends in and its µm (``"µm", 1.0`` when it names none); a name read with
    a factor (``z*2.5``, :func:`scaled_name`) gives ``("×2.5", 2.5)``; ``-start`` after either is read past."""
    name = logged_spec(name) or name
    scaled = scaled_name(name)
    if scaled is not None:
        return f"×{scaled[1]:g}", scaled[1]
    factored = factored_length_unit(name)
    if factored is not None:
        return factored
    unit = named_length_unit(name)
    scale = MICROMETRES_PER_UNIT[unit] if unit else 1.0
    return (unit if scale != 1.0 else "µm"), scale


def factored_length_unit(name: str | None) -> tuple[str, float] | None:
    """``(shown, µm)`` of a name that gives a unit of length with a factor (``dZ [1/1000 mm]``: 1 µm, ``dZ [0.1
    µm]``: 0.1 µm; :mod:`groupfit.unit_factors`); None otherwise."""
    factored = factored_unit(name)
    unit = factored.unit.lower() if factored is not None else None
    if unit not in MICROMETRES_PER_UNIT:
        return None
    return factored.shown, factored.factor * MICROMETRES_PER_UNIT[unit]


def length_unit_named(name: str | None) -> str | None:
    """The unit of length a name gives, as written, with its factor if any (``mm``, ``1/1000 mm``); None when it
    gives none."""
    factored = factored_length_unit(name)
    return factored[0] if factored is not None else named_length_unit(name)


def named_length_unit(name: str | None) -> str | None:
    """The unit of length a name ends in (a key of :data:`MICROMETRES_PER_UNIT`); None when it gives none, or
    gives one with a factor (:func:`factored_length_unit`)."""
    if factored_length_unit(name) is not None:
        return None
    match = LENGTH_UNIT.search(str(name)) if name is not None else None
    return match.group(1).lower() if match else None


def default_temperature_columns(columns: Sequence, exclude: Sequence[str | None] = ()) -> list[str]:
    """The model inputs of a log that does not name them: the columns named like sensors (``T`` followed by
    a digit: ``T1``, ``T2_front``, ``t12_C``); a log with none, those named as temperatures (``Spindle
    [°C]``, ``Temp3``, ``TC2``, ``bed_degC``), an ambient one left out (:func:`groupfit.columns.is_ambient_name`)."""
    excluded = {e for e in exclude if e}
    names = [str(c) for c in columns if c not in excluded]
    sensors = [c for c in names if len(c) > 1 and c[0] in "Tt" and c[1].isdigit()]
    return sensors or [c for c in names if TEMPERATURE_NAME.search(c) and not is_ambient_name(c)]


AMBIENT_NAME = re.compile(
    r"t?(?:amb|ambient|room|air|hall|hallen|shop|umgebung|umgebungs|raum)(?:temp|temperatur|temperature)?"
)
"""A bare name of the air's temperature, its letters only (``Ambient``, ``T_room``, ``air temp``,
``Umgebung``, ``Raumtemperatur``)."""
OTHER_QUANTITY = re.compile(r"humid|\brh\b|press|\bbar\b|\bpa\b|flow|speed|rpm|veloc|%|m/s", re.IGNORECASE)
"""A name of another quantity of the air (humidity, pressure, flow)."""


def ambient_columns(frame: pd.DataFrame, inputs: Sequence[str] = ()) -> list[str]:
    """The columns named as the air's temperature (``Room [°C]``, ``Ambient``, ``T_air``, ``Hall temp``) that
    are not inputs and hold a number on every row, in table order."""
    found = []
    for column in frame.columns:
        name = str(column)
        if column in inputs or not is_ambient_name(name) or OTHER_QUANTITY.search(name):
            continue
        bare = re.sub(r"[^a-z]", "", name.lower())
        if not (TEMPERATURE_NAME.search(name) or AMBIENT_NAME.fullmatch(bare)):
            continue
        if np.isfinite(pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)).all():
            found.append(name)
    return found


OTHER_QUANTITY_NAME = re.compile(
    r"rpm|speed|drehzahl|power|leistung|load|last|current|strom|volt|spannung|press|druck|flow|feed|vorschub|"
    r"pos|axis|achse|humid|feucht|%|torque|moment|count|index|status|state|mode|program|tool|werkzeug|"
    r"\b(?:on|off|id|nr|no|kw|w|a|v|hz)\b|\[(?:w|kw|a|v|hz|bar|mm/min|1/min)\]",
    re.IGNORECASE,
)
"""A name of a quantity that is not a temperature (a speed, a power, a position, a state)."""
PLAUSIBLE_TEMPERATURE_C = (-40.0, 200.0)
"""Readings of a machine's temperature sensors in °C (coolant, structure, bearings, motors)."""


def temperature_like_columns(
    frame: pd.DataFrame, exclude: Sequence[str | None] = (), *, air: bool = False
) -> list[str]:
    """The inputs of a log that names none as a temperature: the numeric columns whose readings look like a
    machine's temperatures in °C (within :data:`PLAUSIBLE_TEMPERATURE_C`, varying, not a setting held at
    levels, not a counter), whose names are not those of a time, an error, the air or another quantity.
    With ``air``, the columns named as the air whose readings look so instead."""
    excluded = {e for e in exclude if e}
    named = set(time_like_columns(frame.columns)) | set(error_like_columns(frame.columns))
    found = []
    for column in frame.columns:
        name = str(column)
        if column in excluded or name in named or is_ambient_name(name) != air or OTHER_QUANTITY_NAME.search(name):
            continue
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
        finite = values[np.isfinite(values)]
        if finite.size < max(3, len(values) // 2) or np.ptp(finite) == 0.0:
            continue
        low, high = PLAUSIBLE_TEMPERATURE_C
        if finite.min() < low or finite.max() > high or is_setting(finite) or is_counter(finite):
            continue
        found.append(name)
    return found


def error_like_columns(columns) -> list[str]:
    """The columns whose names say they hold a thermal error (or any length in µm), in table order."""
    return [
        str(c) for c in columns if ERROR_NAME.match(str(c)) or MICROMETRES_PER_UNIT.get(named_length_unit(c)) == 1.0
    ]


def found_time_column(frame: pd.DataFrame, time: str, label: str, *, default: bool = False) -> tuple[str, str | None]:
    """The time column to read, and a note when it is not the one asked for (see the module docstring).

    ``default``: ``time`` was not asked for (the column a model was fitted with), so a log without it is
    read on the column its name marks, as one without ``time_s`` is. None of the candidates reading as
    increasing times: the first of them, whose error then names it.
    """
    if time in frame.columns or (time != DEFAULT_TIME and not default):
        return time, None
    names = time_like_columns(frame.columns)
    if not names:
        return time, None
    chosen = names[0]
    if len(names) > 1:  # one candidate is read once, by the loader
        chosen = next((name for name in names if _reads_as_time(frame, name, label)), names[0])
    return chosen, f"{label}: time from column '{chosen}' (there is no '{time}'; --time names another)"


def found_error_column(
    frame: pd.DataFrame,
    error: str | None,
    label: str,
    *,
    required: bool = True,
    default: bool = False,
    lengths: Sequence[str] = (),
    time: str | None = None,
) -> tuple[str | None, str | None]:
    """The thermal-error column to read, and a note when it is not the one asked for (module docstring).

    ``default``: ``error`` was not asked for (the column a model was fitted
    with), so a log without it is read on the one column named as an error.
    ``lengths``: the columns a row of units gives in a unit of length, the
    candidates when no column is named as an error.
    Not ``required`` (a replay, which runs without the error too): never a
    guess between several.

    Raises
    ------
    InputError
        The default is absent and several columns could be the error; the error asked for is ``time``, the
        run's time column.
    """
    if error is not None and error == time:
        raise InputError(f"{label}: column '{time}' is the run's time, not the thermal error; name the error's column")
    if error is None or error in frame.columns or not (default or (required and error == DEFAULT_ERROR)):
        return error, None
    names = error_like_columns(frame.columns) or [str(c) for c in lengths]
    if not names:
        return error, None
    if len(names) > 1 and not required:
        listed = ", ".join(names)
        return (
            error,
            f"{label}: there is no column '{error}' and {len(names)} could be the error ({listed}); --error names one",
        )
    if len(names) > 1:
        wide = all(name.startswith(WIDE_PREFIX) for name in names)
        advice = (
            f"columns {WIDE_PREFIX}<mm> are a wide position table's errors, one per axis position: fit them with "
            "--position COLUMN (the name the positions take), or name one with --error COLUMN"
            if wide
            else "name it with --error COLUMN"
        )
        raise InputError(
            f"{label}: there is no column '{DEFAULT_ERROR}' and {len(names)} could be the thermal error "
            f"({', '.join(names)}); {advice}"
        )
    note = f"{label}: thermal error from column '{names[0]}' (there is no '{error}'; --error names another)"
    return names[0], note


def _reads_as_time(frame: pd.DataFrame, name: str, label: str) -> bool:
    trial = frame[[name]].copy()
    try:
        datetimes_to_seconds(trial, name, label)
    except InputError:
        return False
    seconds = pd.to_numeric(trial[name], errors="coerce").to_numpy(dtype=float)
    steps = np.diff(seconds)
    return bool(np.isfinite(seconds).all() and np.all(steps >= 0) and np.mean(steps > 0) >= 0.5)


__all__ = [
    "DEFAULT_ERROR",
    "DEFAULT_TIME",
    "ambient_columns",
    "default_temperature_columns",
    "error_like_columns",
    "found_error_column",
    "found_time_column",
    "factored_length_unit",
    "length_unit",
    "length_unit_named",
    "named_length_unit",
    "scaled_name",
    "temperature_like_columns",
]
