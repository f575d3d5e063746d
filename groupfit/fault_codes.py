"""A temperature column no range option covers and no run-time rule holds (a reference, a sensor the AR(1) model
reads beside its heat): a sensor's fault code in it (-999 °C) is refused, naming its row."""

from __future__ import annotations

import numpy as np

from groupfit.column_values import TEMP_RANGE_C, outside_bounds
from groupfit.errors import InputError


def refuse_implausible_temperature(values: np.ndarray, column: str, source: str, what: str) -> None:
    """Refuse a column's finite readings outside :data:`TEMP_RANGE_C` (a sensor's fault code, -999 °C) where no
    range option applies and no run-time rule holds them, naming the first row; ``what``: the column's role and
    what to do, said after."""
    outside = outside_bounds(values, TEMP_RANGE_C)
    if outside.size:
        low, high = TEMP_RANGE_C
        raise InputError(
            f"{source}: row {outside[0] + 1}, column '{column}' = {values[outside[0]]:g} °C ({outside.size} row(s) "
            f"outside the plausible {low:g} to {high:g} °C: a sensor's fault code?); {what}"
        )


__all__ = ["refuse_implausible_temperature"]
