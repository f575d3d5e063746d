"""A model file's predictions and residual on a run, derived inputs included."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.features import Feature, derived_matrix
from groupfit.modelfile import estimator_from_dict

LiveRule = Callable[[dict, np.ndarray], np.ndarray]


def derived_features(model: dict[str, Any]) -> list[Feature]:
    return [Feature.from_dict(d) for d in model.get("derived_inputs", [])]


def model_inputs(model: dict[str, Any], run: Run) -> np.ndarray:
    """The model's input matrix on a run: measured columns and derived inputs, in the model's order.

    Derived inputs use the model's sampling period, as the run-time rule does
    (a run's own period may differ from it by up to 1 %).
    """
    derived = {f.name: f for f in derived_features(model)}
    columns = []
    for name in model["temps"]:
        if name in derived:
            columns.append(derived_matrix([derived[name]], run.frame, model["sampling_period_s"])[:, 0])
        elif name in run.frame.columns:
            columns.append(run.frame[name].to_numpy(dtype=float))
        else:
            raise InputError(f"{run.source}: column '{name}' that the model uses is missing")
    return np.column_stack(columns)


def predict(model: dict[str, Any], run: Run, live_rule: LiveRule | None = None) -> np.ndarray:
    """Predicted error: groups by the run-time rule when given, else by sample index."""
    X = model_inputs(model, run)
    estimator = estimator_from_dict(model)
    if live_rule is None:
        return estimator.predict(np.nan_to_num(X)) + np.where(np.isfinite(X).all(axis=1), 0.0, np.nan)
    groups = live_rule(model, X)
    return estimator.intercept_[groups] + np.einsum("ij,ij->i", X, estimator.coef_[groups])


def residual(model: dict[str, Any], run: Run, live_rule: LiveRule | None = None) -> np.ndarray:
    if run.error is None:
        raise InputError(f"{run.source}: the run has no error column '{model['error']}'; diagnose needs it")
    return run.error - predict(model, run, live_rule)
