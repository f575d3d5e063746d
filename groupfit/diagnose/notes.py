"""The diagnosis's notes: what it noticed on the way, each of a kind the report can place or leave out."""

from __future__ import annotations

from dataclasses import dataclass

OVERFIT = "overfit"
"""The base model over-fits (the report says it in its head when no effect was added)."""
COLD_START = "cold-start"
"""A validation run starts with a source on without its history (put first when the model got worse)."""
INPUTS = "inputs"
"""A model input looks dead on a run."""
COLUMNS = "columns"
"""A column left out of the candidates, and why."""
HISTORY = "history"
"""A run judged or fitted with the run it continues in front."""
UNSCORED = "unscored"
"""Rows without a measured error: they carry a history and are neither fitted nor scored."""
SCOPE = "scope"
"""What was not tried (transforms of the model's own inputs)."""
AMBIENT = "ambient"
"""Which columns were read as the air, and which as machine sensors."""
CLAMP = "clamp"
"""The compensation's clamp held the prediction on a validation run (scored as replay scores it)."""
FAULTS = "faults"
"""A validation run's reading that is not a number, or outside its valid range: the run-time rule held it, then
was in sensor fault; the samples in fault are not scored, as replay scores the run (:mod:`groupfit.rule_faults`)."""
JOINT = "joint"
"""The joint selection is not expected to carry to a new condition."""


@dataclass(frozen=True)
class Note:
    """One note of the diagnosis: its kind (one of this module's constants) and its text."""

    kind: str
    text: str


def notes_of(kind: str, texts) -> list[Note]:
    """``texts`` as notes of one kind."""
    return [Note(kind, text) for text in texts]
