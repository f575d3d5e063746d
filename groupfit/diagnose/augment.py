"""Add an effect to a model: one more input in every group, groups refitted.

The effect enters as an extra regressor in each soft group, the hard breaks
kept, rather than as a term added to the old prediction: an omitted input that
correlates with the sensors biases their coefficients, and only a joint refit
removes that bias. In a grouped model the effect has one coefficient, the same
in every group, as it was scored (:mod:`groupfit.heldout.design`). The result
is an ordinary model file with one more input, whose ``derived_inputs`` say
how to compute it from the data's columns.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.data import Run
from groupfit.diagnose.residual import ModelLike
from groupfit.features import Feature
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.rewritten import with_slopes


def augment_model(
    model: ModelLike,
    runs: Run | Sequence[Run],
    inputs: np.ndarray | Sequence[np.ndarray],
    feature: Feature,
) -> ModelFile:
    """The model refitted on ``runs`` with ``feature`` as one more input (a model file object).

    Parameters
    ----------
    runs : Run or sequence of Run
        The modelling run, or several runs of a global model (p = 0), stacked.
    inputs : ndarray, shape (N, k), or one per run
        The model's current inputs on each run (see :meth:`groupfit.model.ModelFile.inputs`).
    """
    model = ModelFile.coerce(model)
    if isinstance(runs, Run):
        runs, inputs = [runs], [inputs]
    values = feature_on_runs(feature, runs, model.sampling_period_s)
    X = [np.column_stack([x, v]) for x, v in zip(inputs, values)]
    derived = (*(model.derived_inputs or ()), feature)
    return refit_model(model, runs, X, (*model.temps, feature.name), derived)


def refit_model(
    model: ModelLike,
    runs: Sequence[Run],
    inputs: Sequence[np.ndarray],
    names: Sequence[str],
    derived_inputs: Sequence[Feature],
) -> ModelFile:
    """The model's groups (hard breaks kept) refitted on other inputs, as a model file object."""
    model = ModelFile.coerce(model)
    X, error = np.vstack(inputs), stacked_error(runs)
    derived = {feature.name for feature in derived_inputs}
    estimator = fitted_groups(model, X, error, np.array([name in derived for name in names]))
    return written_model(estimator, model, runs, X, error, names, derived_inputs, model.reference)


def augment_model_over_reference(
    model: ModelLike,
    runs: Sequence[Run],
    inputs: Sequence[np.ndarray],
    feature: Feature,
) -> ModelFile:
    """The model refitted with ``feature`` taken over the model's reference column, written on absolute readings.

    A model of rises over a reference ``R`` (the air) reads ``T_i − R``; a part
    that lags the air adds ``F − R̄``, ``F`` a low-pass or delay of ``R`` and
    ``R̄`` the air through a short low-pass (:func:`steady_reference`). The
    groups are refitted on those rises, then written as the same function of
    absolute readings: ``Σ c_i (T_i − R) + d (F − R̄) = Σ c_i T_i − (Σ c_i) R
    + d F − d R̄``, so the model file reads ``R`` as one more measured input,
    computes ``F`` and ``R̄`` as derived inputs and has no reference. Every
    target evaluates it as it evaluates any model, and its predictions are
    those the effect was scored with.

    Parameters
    ----------
    inputs : sequence of ndarray, shape (N, k)
        The model's current inputs on each run (measured ones as rises over the reference).
    """
    model = ModelFile.coerce(model)
    reference = model.reference
    derived_names = set(model.derived)
    measured = np.array([name not in derived_names for name in model.temps])
    period = model.sampling_period_s
    air = [run.frame[reference].to_numpy(dtype=float) for run in runs]
    smooth = steady_reference(reference)
    lagged = feature_on_runs(feature, runs, period)
    steady = feature_on_runs(smooth, runs, period)
    rises = np.vstack([np.column_stack([x, f - g]) for x, f, g in zip(inputs, lagged, steady)])
    absolute = np.vstack(
        [
            np.column_stack([x + np.where(measured, r[:, None], 0.0), r, f, g])
            for x, f, g, r in zip(inputs, lagged, steady, air)
        ]
    )
    error = stacked_error(runs)
    on_rises = fitted_groups(model, rises, error, np.append(~measured, True))
    slopes = on_rises.coef_
    reference_slope = -slopes[:, :-1][:, measured].sum(axis=1)
    estimator = with_slopes(on_rises, np.column_stack([slopes[:, :-1], reference_slope, slopes[:, -1], -slopes[:, -1]]))
    names = (*model.temps, reference, feature.name, smooth.name)
    derived = (*(model.derived_inputs or ()), feature, smooth)
    return written_model(estimator, model, runs, absolute, error, names, derived, None)


REFERENCE_SMOOTHING_S = 120.0
"""Time constant (s) of the short low-pass of the reference that a lag of it is taken over."""


def steady_reference(reference: str) -> Feature:
    """The reference as a lag of it is taken over: through a 2-minute low-pass.

    ``F − R`` with ``R`` as read carries the noise of every reading of the air at full weight, while the
    lag it measures (a part behind the air) is slow: the fit then trades the lag against that noise, and the
    lag is refused on held-out conditions it would improve. ``F − R̄``, ``R̄`` the air low-passed over a few
    minutes, keeps the lag and drops most of the noise.
    """
    return Feature(reference, "lowpass", tau_s=REFERENCE_SMOOTHING_S)


def feature_on_runs(feature: Feature, runs: Sequence[Run], period: float) -> list[np.ndarray]:
    """``feature`` computed on each run from its own start, at the model's sampling period."""
    return [feature.compute(run.frame[feature.column].to_numpy(dtype=float), period) for run in runs]


def stacked_error(runs: Sequence[Run]) -> np.ndarray:
    return np.concatenate([run.error for run in runs])


def fitted_groups(
    model: ModelFile, X: np.ndarray, error: np.ndarray, shared: np.ndarray | None = None
) -> GroupedRegressor:
    """The model's estimator, hard breaks kept, fitted on the rows whose error is measured.

    ``shared`` marks the columns of ``X`` with one coefficient for every group (the effects of a grouped
    model, :mod:`groupfit.heldout.design`): those coefficients are fitted with every group's own ones on
    the hard groups, then each soft group is refitted on what they leave. Their prediction intervals are
    not those of a per-group fit, so the estimator carries none.
    """
    measured = np.isfinite(error)  # rows without a measured error only carry the derived inputs' history
    estimator = GroupedRegressor.for_model_file(model, fixed_breaks=list(model.breaks), shared_columns=shared)
    return estimator.fit(X[measured], error[measured])


def written_model(
    estimator: GroupedRegressor,
    model: ModelFile,
    runs: Sequence[Run],
    X: np.ndarray,
    error: np.ndarray,
    names: Sequence[str],
    derived_inputs: Sequence[Feature],
    reference: str | None,
) -> ModelFile:
    """The model file of ``estimator`` on inputs ``X`` (the runs stacked), its switching criterion kept if it is
    still an input, else the measured input that moves most."""
    time = np.arange(len(error)) * model.sampling_period_s + runs[0].time[0]
    frame = pd.concat([run.frame for run in runs], ignore_index=True)
    stacked = replace(
        runs[0], time=time, temps=X, temp_names=tuple(names), error=error, frame=frame, reference=reference
    )
    criterion = model.switching.criterion
    if criterion not in names:  # the given criterion was not kept: the measured input that moves most
        derived = {f.name for f in derived_inputs}
        spans = {name: np.ptp(X[:, j]) for j, name in enumerate(names) if name not in derived}
        criterion = max(spans, key=spans.get) if spans else None
    written = estimator.to_model_file(stacked, criterion=criterion)
    return written.replace(derived_inputs=tuple(derived_inputs) or None)
