"""Add an effect to a model: one more input in every group, groups refitted.

The effect enters as an extra regressor in each soft group, the hard breaks
kept, rather than as a term added to the old prediction: an omitted input that
correlates with the sensors biases their coefficients, and only a joint refit
removes that bias. The result is an ordinary model file with one more input,
whose ``derived_inputs`` say how to compute it from the data's columns.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from groupfit.data import Run
from groupfit.features import Feature
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor


def augment_model(model: ModelFile | dict[str, Any], run: Run, inputs: np.ndarray, feature: Feature) -> dict[str, Any]:
    """The model refitted on ``run`` with ``feature`` as one more input (a model file object).

    Parameters
    ----------
    inputs : ndarray, shape (N, k)
        The model's current inputs on ``run`` (see :meth:`groupfit.model.ModelFile.inputs`).
    """
    model = ModelFile.coerce(model)
    values = feature.compute(run.frame[feature.column].to_numpy(dtype=float), model.sampling_period_s)
    X = np.column_stack([inputs, values])
    names = (*model.temps, feature.name)
    estimator = GroupedRegressor(
        n=model.n,
        c=model.c,
        objective=model.objective,
        fit_intercept=model.intercept,
        fixed_breaks=list(model.breaks),
    ).fit(X, run.error)
    augmented_run = replace(run, temps=X, temp_names=names)
    augmented = estimator.to_model_file(augmented_run, criterion=model.switching.criterion)
    return augmented.replace(derived_inputs=(*(model.derived_inputs or ()), feature)).to_dict()
