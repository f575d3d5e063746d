"""A fitted grouped model written on other inputs, without touching the fit it came from."""

from __future__ import annotations

import copy

import numpy as np
from sklearn.utils.validation import check_is_fitted

from groupfit.models.grouped import GroupedRegressor


def with_slopes(estimator: GroupedRegressor, coef: np.ndarray) -> GroupedRegressor:
    """A copy of the fitted ``estimator`` with the slopes ``coef`` (one row per group), groups and intercepts kept:
    the same model written on other inputs (e.g. rises over a reference as absolute readings). It carries no
    prediction intervals: those were of the inputs fitted."""
    check_is_fitted(estimator, "coef_")
    twin = copy.deepcopy(estimator)
    twin.coef_, twin.interval_stats_ = np.asarray(coef, dtype=float), None
    twin.n_features_in_ = twin.coef_.shape[1]
    return twin
