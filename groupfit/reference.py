"""Reference temperatures: the model's inputs as rises over a reference, not absolute readings.

A model fitted on absolute temperatures keeps the ambient of its modelling
day in its intercept: a repeat of the same duty cycle one kelvin warmer is
predicted one kelvin's worth of coefficients off. Controllers compensate from
temperature *differences* for this reason. A model's ``reference`` (a key of
the model file) says what every measured input is taken relative to:

* a column name (``"T_amb"``): each measured input minus that sensor's
  reading of the same sample, usually the ambient air or the machine bed;
* ``"start"``: each measured input minus its own first reading of the run
  (its first good reading, at run time), for machines started cold;
* absent (None): absolute readings, as before.

Derived inputs (:mod:`groupfit.features`) are computed from their source
columns as read: the reference applies to the measured inputs only, before
the dot product. The run-time rule takes a reference column as one more
reading (a faulty reference is a faulty reading) and keeps the first good
reading of every sensor for ``start`` (:mod:`groupfit.runtime`).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Sequence

import numpy as np

from groupfit.data import numeric_column
from groupfit.default_columns import SPEED_NAME, ambient_columns
from groupfit.errors import InputError
from groupfit.fault_codes import refuse_implausible_temperature

START = "start"
"""The reference that takes every input relative to its own first reading."""
NONE_WORDS = ("none", "absolute", "")
"""What ``--reference`` accepts for "no reference" (absolute readings)."""
AMBIENT_COLUMN = "T_amb"
"""The ambient column the FE runs carry; the default reference of a run that has it."""


def parse_reference(text: Any) -> str | None:
    """The reference of a command-line or config value: a column name, ``"start"`` or None."""
    if text is None or text is False:
        return None
    if not isinstance(text, str):
        raise InputError(f"reference {text!r}: give a column name, 'start' or 'none'")
    text = text.strip()
    if text.lower() in NONE_WORDS:
        return None
    if text.lower() == START:
        return START
    return text


def reference_problem(reference: Any, measured_inputs: Sequence[str]) -> str | None:
    """What is wrong with a model file's ``reference`` value, or None."""
    if reference is None:
        return None
    if not isinstance(reference, str) or not reference.strip():
        return "'reference' must be a column name or 'start'"
    if reference.strip().lower() == "none":
        return "'reference' = 'none': write null for a model on absolute readings, or name the reference column"
    if reference in measured_inputs:
        return f"'reference' names the model input '{reference}'; the reference must be another column"
    return None


def is_column_reference(reference: str | None) -> bool:
    """Whether the reference is a sensor column (not None, not ``start``)."""
    return reference is not None and reference != START


def first_finite(values: np.ndarray) -> np.ndarray:
    """Per column of an (N, k) array, its first finite value (NaN for a column without one)."""
    values = np.asarray(values, dtype=float)
    out = np.full(values.shape[1], np.nan)
    finite = np.isfinite(values)
    for j in range(values.shape[1]):
        rows = np.flatnonzero(finite[:, j])
        if rows.size:
            out[j] = values[rows[0], j]
    return out


def referenced(values: np.ndarray, reference: str | None, frame=None, source: str = "the run") -> np.ndarray:
    """The (N, k) measured inputs relative to ``reference`` (a copy; unchanged without a reference).

    ``frame`` (DataFrame-like) supplies the reference column. ``start``
    subtracts each column's first finite value, as the run-time rule
    subtracts each sensor's first good reading.
    """
    values = np.asarray(values, dtype=float)
    if reference is None:
        return values.copy()
    if reference == START:
        return values - first_finite(values)[None, :]
    if frame is None or reference not in frame.columns:
        raise InputError(f"{source}: reference column '{reference}' that the model uses is missing")
    import pandas as pd

    column = pd.to_numeric(frame[reference], errors="coerce").to_numpy(dtype=float)
    return values - column[:, None]


def with_reference(run, reference: str | None, *, faults: bool = False):
    """A :class:`groupfit.data.Run` whose ``temps`` are relative to ``reference`` (its ``frame`` as recorded).

    Refuses a reference that is one of the inputs, a missing column, and a
    reference column with a non-finite value where the inputs are finite,
    unless the run keeps such readings as faults of the run-time rule
    (``faults``: a validation run, read as ``replay`` reads a next run).
    """
    reference = parse_reference(reference)
    if reference is None or run.reference == reference:
        return run
    if run.reference is not None:
        raise InputError(f"{run.source}: the inputs are already relative to '{run.reference}'")
    if reference in run.temp_names:
        raise InputError(
            f"{run.source}: the reference column '{reference}' is also an input; "
            "take it out of --temps or choose another reference"
        )
    refuse_as_temperature(
        run,
        reference,
        "the reference column",
        "name a temperature sensor (the air's, e.g. T_amb) with --reference or --ambient, or --reference none",
    )
    if is_column_reference(reference):
        if reference not in run.frame.columns:
            available = ", ".join(map(str, run.frame.columns))
            raise InputError(f"{run.source}: reference column '{reference}' not found; the columns are: {available}")
        values = numeric_column(
            run.frame, reference, run.source, allow_nonfinite=faults or bool(np.isnan(run.temps).any())
        )
        if not faults:  # a modelling run: the inputs taken against it would carry a fault code
            what = "it is the reference the inputs are taken against: fix or remove those rows, or take the inputs "
            refuse_implausible_temperature(values, reference, run.source, what + "absolute with --reference none")
    temps = referenced(run.temps, reference, run.frame, run.source)
    return dataclasses.replace(run, temps=temps, reference=reference)


def column_role(run, column: str) -> str | None:
    """``"error"`` or ``"time"`` when ``column`` is the run's error or time column, else None: a column no
    temperature can be taken relative to (or be read as)."""
    if column == run.error_name:
        return "error"
    if column == run.time_name:
        return "time"
    return None


def refuse_as_temperature(run, column: str, what: str, todo: str = "name the air's temperature sensor") -> None:
    """Refuse the run's error or time column (:func:`column_role`) where a temperature is asked for: ``what``
    names the option or role it was given as, ``todo`` what to give instead."""
    if SPEED_NAME.search(str(column)):
        raise InputError(f"{run.source}: {what} '{column}' is named as a speed, not a temperature; {todo}")
    role = column_role(run, column)
    if role:
        raise InputError(f"{run.source}: {what} '{column}' is the run's {role}, not a temperature; {todo}")


def default_reference(frame, config_value: Any = None, inputs: Sequence[str] = ()) -> str | None:
    """The reference of a run: the configured one, else ``AMBIENT_COLUMN`` when the run has that column, else
    the one column named as the air's temperature that is not an input
    (:func:`groupfit.default_columns.ambient_columns`)."""
    if config_value is not None:
        return parse_reference(config_value)
    if frame is None:
        return None
    if AMBIENT_COLUMN in frame.columns:
        return AMBIENT_COLUMN
    found = ambient_columns(frame, inputs)
    return found[0] if len(found) == 1 else None


def describe(reference: str | None) -> str:
    """Words for reports and generated comments (ASCII)."""
    if reference is None:
        return "none (absolute readings)"
    if reference == START:
        return "start (each input minus its first good reading since the start)"
    return f"{reference} (each input minus the reading of {reference})"


__all__ = [
    "column_role",
    "refuse_as_temperature",
    "AMBIENT_COLUMN",
    "START",
    "default_reference",
    "with_reference",
    "describe",
    "first_finite",
    "is_column_reference",
    "parse_reference",
    "referenced",
    "reference_problem",
]
