"""An error logged in another unit than µm, read with a factor: ``--error COLUMN*K``.

A 3-D printer logs its probe in motor steps, an encoder in counts, a dial
gauge in inches or with the opposite sign to the error. ``--error
mcu_pos_z*2.5`` reads column ``mcu_pos_z`` ×2.5 as µm (``K``: µm per unit as
logged; a negative ``K`` also flips the sign). The column is read under the
name ``mcu_pos_z*2.5``, which the model file keeps as its ``error``, so
``replay``, ``diagnose`` and ``compare`` read a next run's column with the same
factor; ``replay --probe-column COLUMN*K`` reads logged checks the same way.

A column whose own name ends in ``*K`` is read ×K as well. A column whose
name or row of units gives its unit (``Z_mm``, ``dZ [µm]``) is already read
in µm: a factor on it is refused rather than applied on top.
"""

from __future__ import annotations

import math
from typing import Sequence

import pandas as pd

from groupfit.default_columns import length_unit_named, scaled_name
from groupfit.error_start import logged_spec
from groupfit.errors import InputError


def with_scaled_error(
    frame: pd.DataFrame,
    error: str | None,
    label: str,
    *,
    lengths: Sequence[str] = (),
    required: bool = True,
) -> pd.DataFrame:
    """``frame`` with the column that ``error`` (``COLUMN*K``) scales renamed to ``error``; unchanged when
    ``error`` is a column of its own or asks for no factor.

    ``lengths``: the columns a row of units gives in a unit of length. Not
    ``required`` (a replay, which runs without the error too, or the column a
    model was fitted with): a log without the column is left for the caller.

    Raises
    ------
    InputError
        The factor is 0 or not finite, the column gives its own unit, or
        (``required``) the log has no such column.
    """
    column, _ = scaled_values(frame, error, label)
    if column == error:
        return frame
    factor = scaled_name(error) is not None
    if column not in frame.columns:
        if not required:
            return frame
        available = ", ".join(map(str, frame.columns))
        raise InputError(f"{label}: --error '{error}': column '{column}' not found; the columns are: {available}")
    named = length_unit_named(column)
    if factor and (named is not None or column in lengths):
        how = "given a unit of length by the row of units" if column in lengths else f"in {named} by its name"
        raise InputError(
            f"{label}: --error '{error}': column '{column}' is {how} and read as µm without a factor; "
            f"give --error '{column}'"
        )
    return frame.rename(columns={column: error})


def scaled_values(frame: pd.DataFrame, name: str | None, label: str) -> tuple[str | None, float]:
    """The column ``name`` reads and its factor to µm: ``("z", 2.5)`` for ``z*2.5`` when the frame has no
    column of that name, ``(name, 1.0)`` otherwise (its unit, if any, is the caller's); a factor of 0 or not
    finite refused."""
    scaled = scaled_name(name)
    if name in frame.columns:
        return name, 1.0
    if scaled is None:
        return logged_spec(name) or name, 1.0
    column, factor = scaled
    check_factor(name, column, factor, label)
    return column, factor


def check_factor(name: str, column: str, factor: float, label: str) -> None:
    """Refuse a factor that is 0 or not finite (one clear line naming ``name``)."""
    if not (math.isfinite(factor) and factor != 0.0):
        raise InputError(
            f"{label}: '{name}': the factor {factor:g} must be a finite number other than 0 "
            f"(µm per unit of '{column}' as logged, e.g. '{column}*2.5')"
        )


def factor_problem(name: object) -> str | None:
    """What is wrong with a model file's ``error`` that asks for a factor (None: nothing, or no factor)."""
    scaled = scaled_name(name) if isinstance(name, str) else None
    if scaled is None or (math.isfinite(scaled[1]) and scaled[1] != 0.0):
        return None
    return f"error = {name!r}: its factor must be a finite number other than 0"


__all__ = ["check_factor", "factor_problem", "scaled_values", "with_scaled_error"]
