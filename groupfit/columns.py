"""The roles of a run's columns: which can explain a thermal error and which cannot.

A column is a *cause* the controller can read (a temperature, a speed, the
on/off of a heat source) unless it is a displacement (another probe's error),
not numeric, partly non-finite (a failing sensor), 0 throughout (a dead sensor),
a temperature stuck at one value, or a sample index (it grows by one step every
row). Another constant is kept: a heater switched on at the start at its
set-point heats from rest.
The diagnosis draws its candidates from these columns and the held-out folds
(:mod:`groupfit.heldout.folds`) their operating conditions.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.errors import InputError

DISPLACEMENT_SUFFIXES = ("_um", "_mm", "_µm")
AMBIENT_WORDS = (
    "room", "air", "hall", "shop", "chamber", "enclosure", "umgebung", "raumtemp",
    "环境", "環境", "室温", "気温", "外气", "실온", "실내", "주변", "외기", "환경",
    "окружающ", "воздух", "помещени", "цех",
)  # fmt: skip
"""A column whose name holds one of these is an ambient temperature: an enclosure's chamber (a 3-D printer's
``chamber_t``) is the air around the frame inside it."""
AMBIENT_ABBREVIATION = re.compile(r"(?:^|[^a-z])t?amb")
"""``amb`` at the start of a word, or after a lone ``t`` (``T_amb``, ``Tamb``, ``Ambient``), not inside one
(``lambda``, ``camber``)."""


def is_ambient_name(column: str) -> bool:
    lowered = column.lower()
    return any(word in lowered for word in AMBIENT_WORDS) or AMBIENT_ABBREVIATION.search(lowered) is not None


def is_sensor_column(column: str) -> bool:
    """A temperature sensor of the machine (``T3``, ``t12_C``), not the ambient: a symptom rather than a cause."""
    lowered = column.lower()
    return len(column) > 1 and lowered[0] == "t" and lowered[1].isdigit() and not is_ambient_name(column)


def is_temperature_name(column: str) -> bool:
    """A temperature reading by its name (``T3``, ``T_stuck``, ``bed_temp``): constant, it is a stuck sensor, not a
    set-point."""
    lowered = column.lower()
    return (len(column) > 1 and lowered[0] == "t" and (lowered[1].isdigit() or lowered[1] == "_")) or "temp" in lowered


def is_displacement(column: str) -> bool:
    lowered = column.lower()
    return lowered.endswith(DISPLACEMENT_SUFFIXES) or lowered.startswith(("disp", "error"))


MARKER_MAGNITUDE = 1.0e12
"""A value beyond this magnitude is a logger's marker (3e38, 1e308), no temperature, speed or power."""


def usable_columns(frame: pd.DataFrame, exclude: set[str]) -> tuple[list[str], list[str]]:
    """Columns that can explain a residual, and a note for each one left out."""
    usable, notes = [], []
    for column in frame.columns:
        if column in exclude:
            continue
        if is_displacement(column):
            notes.append(f"column '{column}' left out: a displacement, not a cause the controller can read")
            continue
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
        bad = int((~np.isfinite(values)).sum())
        if bad == len(values):
            notes.append(f"column '{column}' left out: not numeric or empty")
        elif bad:
            notes.append(f"column '{column}' left out: {bad} non-finite value(s) (a failing sensor?)")
        elif np.max(np.abs(values)) > MARKER_MAGNITUDE:
            row = int(np.argmax(np.abs(values) > MARKER_MAGNITUDE))
            notes.append(
                f"column '{column}' left out: {values[row]:g} at row {row + 1} is no reading (a logger's overflow "
                "marker?)"
            )
        elif np.ptp(values) == 0.0 and values[0] == 0.0:
            notes.append(f"column '{column}' left out: constant 0 (a dead sensor, or a source never on?)")
        elif np.ptp(values) == 0.0 and is_temperature_name(column):
            notes.append(f"column '{column}' left out: constant {values[0]:g} (a stuck temperature sensor?)")
        elif np.ptp(values) == 0.0:
            usable.append(column)
            notes.append(
                f"column '{column}' kept though constant ({values[0]:g}): a source switched on at the start (a "
                "set-point) heats from rest, and its lags from rest carry that; a dead sensor shows no effect"
            )
        elif is_counter(values):
            notes.append(f"column '{column}' left out: a sample index or clock (it grows by one step every row)")
        else:
            usable.append(column)
    return usable, notes


def renamed_from(column: str, columns: Sequence) -> str | None:
    """The one column whose name is ``column`` with words added (``T2_spindle``, ``T2 [°C]`` for ``T2``), or
    the reverse; None when there is none or more than one."""
    wanted = column.strip().casefold()
    near = [
        str(c)
        for c in columns
        if (name := str(c).strip().casefold()) != wanted
        and (re.match(re.escape(wanted) + r"[\W_]", name) or re.match(re.escape(name) + r"[\W_]", wanted))
    ]
    return near[0] if len(near) == 1 else None


def is_counter(values: np.ndarray) -> bool:
    """Whether a column grows by the same step on every row (a sample index, a second clock): not a cause."""
    if len(values) < 3:
        return False
    step = np.diff(values)
    return bool(step[0] > 0 and np.all(np.abs(step - step[0]) <= 1e-9 * max(abs(step[0]), 1.0)))


def input_order(expected: Sequence[str], given: Sequence[str], label: str) -> list[int]:
    """Where each of the modelling run's inputs ``expected`` is among a run's inputs ``given`` (the same
    columns in another order are the same inputs); a run with other inputs is refused, saying how they differ."""
    if sorted(given) == sorted(expected) and len(set(given)) == len(given):
        return [list(given).index(name) for name in expected]
    missing = [c for c in expected if c not in given]
    added = [c for c in given if c not in expected]
    parts = [f"missing {', '.join(missing)}"] if missing else []
    parts += [f"not in the modelling run: {', '.join(added)}"] if added else []
    raise InputError(
        f"{label}: temperature columns differ from the modelling run's ({'; '.join(parts)}); name the same inputs "
        "in both runs (--temps A,B,C)"
    )


def aligned_inputs(runs: Sequence) -> list:
    """Runs to be joined, every one's inputs in the first's order (the same columns in another order are the
    same inputs); a run with other inputs is refused, naming what it lacks and what it adds."""
    first, *others = runs
    aligned = [first]
    for run in others:
        if run.temp_names != first.temp_names:
            order = input_order(first.temp_names, run.temp_names, run.source)
            run = dataclasses.replace(run, temps=run.temps[:, order], temp_names=first.temp_names)
        aligned.append(run)
    return aligned


def shared_default_inputs(runs: Sequence) -> list:
    """Runs whose default inputs differ only because loading left a column out of some of them (stuck, dead)
    restricted to the inputs every run kept, each with a note naming what was left out and where; runs that
    differ otherwise are returned as they are (:func:`aligned_inputs` then names the difference)."""
    kept = [name for name in runs[0].temp_names if all(name in run.temp_names for run in runs)]
    dropped = sorted({name for run in runs for name in run.temp_names if name not in kept})
    if not dropped or not kept or any(name not in run.frame.columns for run in runs for name in dropped):
        return list(runs)
    where = [run.source for run in runs if any(name not in run.temp_names for name in dropped)]
    note = (
        f"{', '.join(dropped)} left out of the inputs of every run: loading left it out of {', '.join(where)} "
        "(see the note there), and the runs must share their inputs; --temps names the inputs"
    )
    restricted = []
    for run in runs:
        order = [list(run.temp_names).index(name) for name in kept]
        run = dataclasses.replace(run, temps=run.temps[:, order], temp_names=type(run.temp_names)(kept))
        restricted.append(run)
    restricted[0] = dataclasses.replace(restricted[0], notes=(*restricted[0].notes, note))
    return restricted
