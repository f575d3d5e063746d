"""Global multiple linear regression: the grouped model with no breaks, with its statistics."""

from __future__ import annotations

import numpy as np
from sklearn.utils.validation import check_array, check_is_fitted

from groupfit.models.grouped import GroupedRegressor


class MLR(GroupedRegressor):
    """One least-squares coefficient vector for the whole run (p = 0).

    Besides the fit, ``fit`` computes what a compensation engineer checks
    before trusting a regression (statsmodels OLS): standard errors and
    t-tests of the coefficients, the overall F-test, and prediction
    intervals through :meth:`prediction_interval`.

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
    statistics_ : dict
        ``terms`` (name, estimate, std_error, t, p_value per coefficient),
        ``f_value``, ``f_p_value``, ``r_squared``, ``sigma_um``, ``dof``.
    """

    def __init__(self, objective: str = "sae", fit_intercept: bool = True):
        super().__init__(p=0, n=0, c=0.0, objective=objective, fit_intercept=fit_intercept, search="exact")

    def fit(self, X, y, progress=None):
        import statsmodels.api as sm

        super().fit(X, y, progress=progress)
        X = check_array(X)
        y = np.asarray(y, dtype=float).ravel()
        design = sm.add_constant(X, has_constant="add") if self.fit_intercept else X
        self.ols_ = sm.OLS(y, design).fit()
        names = list(getattr(self, "feature_names_in_", [f"x{i + 1}" for i in range(X.shape[1])]))
        names = (["const"] if self.fit_intercept else []) + [str(n) for n in names]
        self.statistics_ = {
            "terms": [
                {"name": name, "estimate": float(b), "std_error": float(se), "t": float(t), "p_value": float(pv)}
                for name, b, se, t, pv in zip(
                    names, self.ols_.params, self.ols_.bse, self.ols_.tvalues, self.ols_.pvalues
                )
            ],
            "f_value": float(self.ols_.fvalue) if self.fit_intercept else None,
            "f_p_value": float(self.ols_.f_pvalue) if self.fit_intercept else None,
            "r_squared": float(self.ols_.rsquared),
            "sigma_um": float(np.sqrt(self.ols_.scale)),
            "dof": float(self.ols_.df_resid),
        }
        return self

    def prediction_interval(self, X, alpha: float = 0.05) -> np.ndarray:
        """Lower and upper ``1 − alpha`` prediction bounds for new samples, shape (n, 2)."""
        import statsmodels.api as sm

        check_is_fitted(self, "ols_")
        X = check_array(X)
        design = sm.add_constant(X, has_constant="add") if self.fit_intercept else X
        frame = self.ols_.get_prediction(design).summary_frame(alpha=alpha)
        return frame[["obs_ci_lower", "obs_ci_upper"]].to_numpy()
