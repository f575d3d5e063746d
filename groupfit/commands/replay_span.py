"""Where a replayed run leaves the modelling run's span: its inputs, and the reference the inputs are taken against.

``fit`` keeps the span of every input over the modelling run in the model file
(:mod:`groupfit.heldout.span`); a replay names the inputs, and the reference
column, that a run takes beyond it. A stream and a table of check runs (every
row at its own position) are checked alike, sample by sample or row by row.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from groupfit.errors import InputError
from groupfit.heldout.span import REFERENCE_TOLERANCE, SPAN_KEY, beyond_span, span_note
from groupfit.model import ModelFile
from groupfit.runtime import FAULT_HELD, FAULT_SENSOR, Replay


def modelling_span(model: ModelFile) -> dict[str, Any]:
    """The modelling run's span of every input (and of the reference) the model file keeps; empty without one."""
    return (model.training or {}).get(SPAN_KEY) or {}


def span_readings(model: ModelFile, frame, source: str) -> tuple[np.ndarray, np.ndarray | None] | None:
    """The model's inputs over ``frame`` and the readings of the reference column the inputs are taken against
    (None when the model keeps no span of it or the frame has no such column); None when the inputs cannot be
    formed from the frame."""
    try:
        inputs = np.array(model.inputs(frame, source), dtype=float)
    except InputError:
        return None
    reference = model.reference
    if reference in modelling_span(model) and reference not in model.temps and reference in frame.columns:
        return inputs, frame[reference].to_numpy(dtype=float)
    return inputs, None


def beyond_modelling_range(
    model: ModelFile, inputs: np.ndarray, reference: np.ndarray | None, fault: np.ndarray
) -> dict[str, Any]:
    """``beyond_modelling_range`` (the reference's entries with ``"reference": true``) and a note, over the samples
    (or rows) of ``inputs``; those the rule met as a sensor fault or on held readings (``fault``) are not the
    machine's state and are left out."""
    span = modelling_span(model)
    not_the_machine = (np.asarray(fault) & (FAULT_SENSOR | FAULT_HELD)) != 0
    inputs = np.array(inputs, dtype=float)
    inputs[not_the_machine] = np.nan
    beyond = beyond_span(span, model.temps, inputs)
    if reference is not None:
        readings = np.where(not_the_machine, np.nan, np.asarray(reference, dtype=float))
        moved = beyond_span(span, [model.reference], readings[:, None], REFERENCE_TOLERANCE)
        beyond += [{**b, "reference": True} for b in moved]
    note = span_note(beyond, len(not_the_machine))
    return {"beyond_modelling_range": beyond, "notes": [note] if note else []}


def range_check(model: ModelFile, run, replay: Replay) -> dict[str, Any]:
    """The inputs of ``run`` beyond the modelling run's span (kept by ``fit`` in the model file), and a note;
    samples the run-time rule met as a sensor fault or on held readings are not the machine's state."""
    if not modelling_span(model):
        return {}
    readings = span_readings(model, run.frame, run.source)
    if readings is None:
        return {}
    return beyond_modelling_range(model, *readings, replay.fault)


__all__ = ["beyond_modelling_range", "modelling_span", "range_check", "span_readings"]
