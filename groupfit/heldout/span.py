"""The modelling run's span of every input, and a next run that leaves it (where no estimate holds)."""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

SPAN_KEY = "input_span"
"""The model file's ``training`` key: ``{input: [lowest, highest]}`` over the modelling run."""
TOLERANCE = 0.05
"""A reading beyond the span by more than this share of the span's width leaves the modelling range."""
REFERENCE_TOLERANCE = 1.0
"""The same for the reference column (the air the inputs are taken against): another day's air is seldom
inside one day's, and a level beyond it by less than the modelling day's own swing is the variation the
model has met; beyond by more, a machine whose error follows its parts' own temperatures is off."""


def input_span(names: Sequence[str], inputs: np.ndarray) -> dict[str, list[float]]:
    """The lowest and highest finite value of every input column."""
    inputs = np.asarray(inputs, dtype=float)
    return {
        name: [float(np.nanmin(inputs[:, j])), float(np.nanmax(inputs[:, j]))]
        for j, name in enumerate(names)
        if np.isfinite(inputs[:, j]).any()
    }


def reference_span(frames: Sequence, reference: str | None, inputs: Sequence[str]) -> dict[str, list[float]]:
    """The span over ``frames`` (the modelling runs' tables) of the reference column the inputs are taken
    against (``T_amb`` of "minus T_amb"), by its own name: a run on a day warmer or colder than the modelling
    day leaves it while the referenced inputs may not. Empty for no reference, the start, or a reference that
    is also an input."""
    if reference in (None, "start") or reference in inputs:
        return {}
    values = [np.asarray(frame[reference], dtype=float) for frame in frames if reference in frame.columns]
    return input_span([reference], np.concatenate(values)[:, None]) if values else {}


def training_span(
    names: Sequence[str], inputs: np.ndarray, frames: Sequence, reference: str | None
) -> dict[str, list[float]]:
    """What the model file keeps as ``training.input_span``: the span of every input over the modelling runs
    (``inputs``, as the model reads them) and that of the reference column they are taken against
    (:func:`reference_span`, over the runs' tables ``frames``)."""
    return {**input_span(names, inputs), **reference_span(frames, reference, names)}


def beyond_span(
    span: Mapping[str, Sequence[float]], names: Sequence[str], inputs: np.ndarray, tolerance: float = TOLERANCE
) -> list[dict[str, Any]]:
    """The inputs of a run that leave the modelling span by more than ``tolerance`` of its width: name, span,
    the run's range, samples outside."""
    inputs = np.asarray(inputs, dtype=float)
    out = []
    for j, name in enumerate(names):
        if name not in span:
            continue
        low, high = (float(v) for v in span[name])
        margin = tolerance * max(high - low, 1e-9)
        values = inputs[:, j]
        outside = np.isfinite(values) & ((values < low - margin) | (values > high + margin))
        if outside.any():
            out.append(
                {
                    "input": name,
                    "span": [low, high],
                    "run": [float(np.nanmin(values)), float(np.nanmax(values))],
                    "samples": int(outside.sum()),
                }
            )
    return out


def span_note(beyond: list[dict[str, Any]], n_samples: int) -> str | None:
    """A note on a run outside the modelling range, and what run to record next; None when it stays inside."""
    if not beyond:
        return None
    parts = ", ".join(
        f"{b['input']} {b['run'][0]:.3g}..{b['run'][1]:.3g} (modelled {b['span'][0]:.3g}..{b['span'][1]:.3g}; "
        f"{b['samples']} of {n_samples} samples outside)"
        for b in beyond
    )
    return (
        f"this run leaves the modelling range: {parts}; the model extrapolates there and the expected next-run "
        "error from fit does not cover it; record a modelling run that covers this range and refit"
    )


__all__ = [
    "REFERENCE_TOLERANCE",
    "SPAN_KEY",
    "beyond_span",
    "input_span",
    "reference_span",
    "span_note",
    "training_span",
]
