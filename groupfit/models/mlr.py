"""Global multiple linear regression: the grouped model with no breaks."""

from __future__ import annotations

from groupfit.models.grouped import GroupedRegressor


class MLR(GroupedRegressor):
    """One least-squares coefficient vector for the whole run (p = 0).

    Parameters
    ----------
    objective : {"sae", "sse"}
        Which residual sum ``objective_value_`` reports.
    fit_intercept : bool

    Attributes
    ----------
    coef_ : ndarray, shape (1, n_features)
    intercept_ : ndarray, shape (1,)
    objective_value_ : float
    residuals_ : ndarray
    """

    def __init__(self, objective: str = "sae", fit_intercept: bool = True):
        super().__init__(p=0, n=0, c=0.0, objective=objective, fit_intercept=fit_intercept, search="exact")
