"""Is the model's reference temperature right? Rises over a reference sensor against absolute readings.

``groupfit fit`` takes every input relative to ``T_amb`` when a run has that
column (:mod:`groupfit.reference`): right for a machine whose error follows
its temperatures *over the air* (a probe and workpiece that sit in the air,
the error zeroed at ambient equilibrium), wrong for one whose error follows
the absolute temperatures of its parts (the error measured against a fixed
reference). The two read the same on a modelling run whose air stays
constant; when the air moves, the rises impose the reference sensor with the
weight −Σβ on a machine that does not feel it that way, and every effect
searched for afterwards is judged against that wrong weight (the reference
column itself then looks like the missing effect).

The check scores the model refitted on absolute readings on the diagnosis's
held-out folds, against the model as given, and faces it with the test of a
first effect. Only a clear win drops the reference: where the run cannot
tell the two apart, the given reference stays.

A grouped model is compared as one group (:func:`global_view`): each group's
own intercept and weights follow the level of the air over its stretch of
the run, so the held-out folds, which lie inside the groups, cannot see the
level the reference sets, while the next run on a warmer day does. The
question of the reference is one of physics, not of grouping; one set of
coefficients over the whole run answers it.

Before an effect is in, both readings may miss it so badly that neither wins,
and with the wrong reference kept the effect is then not found at all. So
when the reference survives the diagnosis, the diagnosis is run again from
absolute readings, and the two end models, each with its own effects, face
the same test (:func:`groupfit.diagnose.loop.absolute_branch`).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from groupfit.data import Run
from groupfit.diagnose.augment import refit_model
from groupfit.diagnose.candidates import Candidate, candidate_of_fold_sse
from groupfit.diagnose.residual import model_inputs
from groupfit.features import Feature
from groupfit.heldout.reference_choice import SIGNAL_TO_NOISE, ambient_signal_to_noise
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.model import ModelFile
from groupfit.reference import is_column_reference


def droppable_reference(model: ModelFile, runs: Sequence[Run]) -> str | None:
    """The model's reference sensor when every run has that column, else None (no reference, or ``start``)."""
    reference = model.reference
    if not is_column_reference(reference):
        return None
    return reference if all(reference in run.frame.columns for run in runs) else None


def steady_reference(reference: str, runs: Sequence[Run]) -> str | None:
    """Why ``runs`` cannot tell rises over ``reference`` from absolute readings: its reading stays within its
    noise (the test of :func:`groupfit.heldout.reference_choice.ambient_signal_to_noise`); None when it moves.

    Rises and absolute readings then differ by a constant and the reference's noise: a held-out gain of
    absolute readings is that noise taken out, and the model on them keeps this day's air level in its
    intercept, off by the whole change on a day at another level.
    """
    spread, ratio = ambient_signal_to_noise([run.frame[reference].to_numpy(dtype=float) for run in runs])
    if ratio > SIGNAL_TO_NOISE:
        return None
    return (
        f"`{reference}` stays within its noise (sd {spread:.2g} °C, {ratio:.2g} × its sample-to-sample scatter): "
        "the run cannot tell rises over it from absolute readings, and a model on absolute readings would be off "
        "by the whole change on a day at another air level"
    )


def absolute_model(model: ModelFile, runs: Sequence[Run]) -> tuple[ModelFile, list[np.ndarray]]:
    """The model refitted on ``runs`` with its measured inputs as read (no reference), hard breaks kept; and
    its inputs on each run."""
    absolute = model.replace(reference=None)
    inputs = [model_inputs(absolute, run) for run in runs]
    return refit_model(absolute, list(runs), inputs, absolute.temps, absolute.derived_inputs or ()), inputs


def absolute_candidate(reference: str, given: HeldOutScorer, absolute: HeldOutScorer) -> Candidate:
    """Absolute readings scored like an effect: the share of the given model's held-out error they remove."""
    return candidate_of_fold_sse(Feature(reference), absolute.base_sse, given)


def global_view(model: ModelFile) -> ModelFile:
    """The model's inputs, intercept and effects as one group: the design the reference is judged in (a view
    for :mod:`groupfit.heldout.design`, not a model file to write)."""
    return model.replace(p=0, breaks=())
