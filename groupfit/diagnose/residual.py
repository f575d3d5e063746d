"""A model file's predictions and residual on a run, derived inputs included."""

from __future__ import annotations

from typing import Any, Callable, Mapping

import numpy as np

from groupfit.clamped_scores import within_compensation_clamp
from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.rule_faults import has_faulty_readings, replayed_prediction

LiveRule = Callable[[ModelFile, np.ndarray], np.ndarray]
ModelLike = ModelFile | Mapping[str, Any]


def model_inputs(model: ModelLike, run: Run) -> np.ndarray:
    """The model's input matrix on a run: measured columns and derived inputs, in the model's order."""
    return ModelFile.coerce(model).inputs(run.frame, run.source)


def predict(model: ModelLike, run: Run, live_rule: LiveRule | None = None, *, next_run: bool = False) -> np.ndarray:
    """Predicted error: groups by the run-time rule when given, with its bumpless transfer after each switch (what
    ``groupfit replay`` computes), else by sample index (the offline model, as fitted).

    With the rule, a run with an input that is not a number (a validation
    run's sensor fault) is replayed by the rule itself, as ``replay`` replays
    it: the reading held, then NaN where the rule is in sensor fault (not
    scored; :mod:`groupfit.rule_faults`). So is a ``next_run`` (a validation
    run) with a finite reading outside its valid range (a sensor's fault code).
    """
    model = ModelFile.coerce(model)
    X = model.inputs(run.frame, run.source)
    if live_rule is None:
        return model.predict(np.nan_to_num(X)) + np.where(np.isfinite(X).all(axis=1), 0.0, np.nan)
    if not np.isfinite(X).all() or (next_run and has_faulty_readings(model, run)):
        return replayed_prediction(model, run)[0]
    return model.predict(X, live_rule(model, X), transfer=True)


def corrected(model: ModelLike, prediction: np.ndarray) -> np.ndarray:
    """What the controller corrects of ``prediction``, within the model file's compensation clamp, as in replay."""
    return within_compensation_clamp(prediction, ModelFile.coerce(model).switching)


def clamped_samples(model: ModelLike, run: Run, live_rule: LiveRule | None = None, skip: int = 0) -> int:
    """On how many samples of validation run ``run`` (after its first ``skip``) the compensation's clamp holds the
    prediction."""
    prediction = predict(model, run, live_rule, next_run=True)[skip:]
    finite = np.isfinite(prediction)
    return int(np.sum(corrected(model, prediction[finite]) != prediction[finite]))


def residual(model: ModelLike, run: Run, live_rule: LiveRule | None = None, *, next_run: bool = False) -> np.ndarray:
    """The measured error less what the controller corrects (:func:`predict`, ``next_run`` as it takes it)."""
    model = ModelFile.coerce(model)
    if run.error is None:
        raise InputError(f"{run.source}: the run has no error column '{model.error}'; diagnose needs it")
    return run.error - corrected(model, predict(model, run, live_rule, next_run=next_run))
