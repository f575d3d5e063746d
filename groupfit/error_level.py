"""An error column whose level or size says it is not a thermal error in µm.

Two logs a user brings read as µm without complaint and give a model that
cannot go onto a machine:

* a probe's or an axis's **position logged from the machine's zero** within
  the plausible ±100 mm (``probe_z_mm`` at 12.34 mm, drifting by 20 µm): every
  reading lies millimetres from zero while they move by micrometres. A model
  of it compensates 12 mm. It gets a note that ``--error 'COLUMN-start'``
  (the drift since the run's start) reads the drift; it is not refused, since
  a printer's step count logged from its zero is modelled as logged by users
  who replay it the same way;
* an **error in mm under a name that gives no unit** that moves by 0.1-1 mm:
  read as µm it spans 0.1-1 µm while the inputs move by tens of kelvin, a
  thousandth of what thermal drift shows per kelvin. It gets a note that says
  how to read it ×1000.
"""

from __future__ import annotations

import numpy as np

from groupfit.column_values import unit_note
from groupfit.default_columns import factored_length_unit, named_length_unit, scaled_name
from groupfit.error_start import is_from_start

LEVEL_FLOOR_UM = 1000.0
"""An error every reading of which lies farther from zero than this (µm) ..."""
LEVEL_SHARE = 0.1
"""... while all of them span less than this share of the nearest one's distance is a position from another zero."""

SMALLEST_DRIFT_PER_KELVIN_UM = 0.05
"""The least error span per kelvin of the inputs' span (µm/K) a thermal error shows; the shipped runs and the
measured spindle test show 1.0-3.3, an error in mm read as µm a thousandth of that."""
INPUT_SPAN_PERCENTILES = (1.0, 99.0)
"""An input's span for the ratio: between these percentiles, so that a glitch (450 °C for one sample) does not
count."""
SMALLEST_INPUT_SPAN_K = 1.0
"""The inputs must move by this much (K) before the error's span per kelvin says anything."""


def position_level_note(values: np.ndarray, column: str, label: str) -> str | None:
    """The note of an error (µm) every reading of which lies more than :data:`LEVEL_FLOOR_UM` from zero while all
    of them span less than :data:`LEVEL_SHARE` of the nearest one's distance; None otherwise."""
    measured = values[np.isfinite(values)]
    if measured.size < 2:
        return None
    nearest = float(np.min(np.abs(measured)))
    same_side = bool(np.all(measured > 0) or np.all(measured < 0))
    spread = float(np.ptp(measured))
    if not (same_side and nearest > LEVEL_FLOOR_UM and spread < LEVEL_SHARE * nearest):
        return None
    return (
        f"{label}: column '{column}': every reading lies at least {nearest:.6g} µm from zero while they span only "
        f"{spread:.4g} µm, read as logged: a position from the machine's zero, not a thermal error? The model "
        f"then compensates that level, and a run homed anew is off by the change; --error '{column}-start' reads "
        f"the drift since the run's start ('{column}*K-start' when it counts steps or encoder counts of K µm each)"
    )


def _drift_per_kelvin_note(name: str, label: str, values: np.ndarray, temps: np.ndarray) -> str | None:
    """The note of an error whose span per kelvin of the inputs' span is below a thermal error's."""
    measured = values[np.isfinite(values)]
    if measured.size < 2 or temps.size == 0:
        return None
    finite = np.where(np.isfinite(temps), temps, np.nan)
    spans = [
        float(np.diff(np.nanpercentile(column, INPUT_SPAN_PERCENTILES))[0])
        for column in finite.T
        if np.isfinite(column).any()
    ]
    input_span = max(spans, default=0.0)
    span = float(np.ptp(measured))
    if input_span < SMALLEST_INPUT_SPAN_K or span <= 0.0:
        return None
    per_kelvin = span / input_span
    if per_kelvin >= SMALLEST_DRIFT_PER_KELVIN_UM:
        return None
    return (
        f"{label}: column '{name}' spans {span:.3g} µm over the run, read as µm (its name gives no unit), while the "
        f"inputs move by {input_span:.3g} K: {per_kelvin:.2g} µm per K, far less than thermal drift shows "
        f"(the shipped runs 1-3 µm per K); if it is in mm, name it '{name}_mm' (or '{name} [mm]') or give "
        f"--error '{name}*1000' to read it ×1000"
    )


def error_unit_note(name: str | None, label: str, values: np.ndarray, temps: np.ndarray) -> str | None:
    """The note of an error column read in another unit than µm, or whose level or size says it may not be a
    thermal error in µm (:func:`groupfit.column_values.unit_note`, then :func:`position_level_note`, then the
    span per kelvin of the inputs); None otherwise."""
    note = unit_note(name, label, values)
    level = position_level_note(values, name, label) if name is not None and not is_from_start(name) else None
    if level is not None:
        return f"{note}; {level}" if note else level
    if note is not None or name is None or scaled_name(name) is not None:
        return note
    if named_length_unit(name) is not None or factored_length_unit(name) is not None:
        return None
    return _drift_per_kelvin_note(name, label, values, temps)


__all__ = ["error_unit_note", "position_level_note"]
