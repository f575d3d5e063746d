"""Global multiple linear regression: the grouped model with no breaks, with its statistics."""

from __future__ import annotations

import warnings

import numpy as np
import statsmodels.api as sm
from scipy import stats
from scipy.linalg import solve_triangular
from sklearn.utils.validation import check_array, check_is_fitted
from statsmodels.tools.sm_exceptions import SingularMatrixWarning

from groupfit.errors import InputError
from groupfit.models.grouped import GroupedRegressor


def ols_statistics(ols, names: list[str], *, fit_intercept: bool) -> dict:
    """The tests of a fitted statsmodels OLS: t and p per coefficient, F and its p, R² and adjusted R².

    Without an intercept R², adjusted R² and F are statsmodels' uncentred ones (against E = 0).
    """
    return {
        "terms": [
            {"name": name, "estimate": float(b), "std_error": float(se), "t": float(t), "p_value": float(pv)}
            for name, b, se, t, pv in zip(names, ols.params, ols.bse, ols.tvalues, ols.pvalues)
        ],
        "f_value": float(ols.fvalue) if ols.df_model > 0 else None,
        "f_p_value": float(ols.f_pvalue) if ols.df_model > 0 else None,
        "f_dof": [float(ols.df_model), float(ols.df_resid)],
        "r_squared": float(ols.rsquared),
        "adjusted_r_squared": float(ols.rsquared_adj),
        "sigma_um": float(np.sqrt(ols.scale)),
        "dof": float(ols.df_resid),
        "centred": bool(fit_intercept),
        "dependent_inputs": dependent_columns(ols.model.exog, names),
    }


def dependent_columns(design: np.ndarray, names: list[str]) -> list[str]:
    """The columns of ``design`` in a linear dependence (a sensor logged twice, one the sum of others), by
    name; empty when the design has full column rank. Their t-tests split one effect arbitrarily."""
    scaled = design / np.maximum(np.linalg.norm(design, axis=0), np.finfo(float).tiny)
    _, singular, vt = np.linalg.svd(scaled, full_matrices=False)
    null = vt[singular < singular[0] * max(design.shape) * np.finfo(float).eps * 1e3]
    if not null.size:
        return []
    involved = np.any(np.abs(null) > 1e-6, axis=0)
    return [name for name, flag in zip(names, involved) if flag]


def design_matrix(X, *, fit_intercept: bool) -> np.ndarray:
    X = check_array(X)
    return sm.add_constant(X, has_constant="add") if fit_intercept else X


def backward_elimination(X, y, names: list[str], *, alpha: float, fit_intercept: bool = True) -> dict:
    """Drop inputs by their t-tests, one at a time, until every input's p-value is at most ``alpha``.

    Each round refits the regression (statsmodels OLS) on the inputs left and drops
    the one with the largest p-value above ``alpha`` (the intercept is never
    dropped); at least one input stays. Inputs in a linear dependence (a sensor
    logged twice, one the sum of others), whose t-tests split one effect
    arbitrarily, go first, the last of them in each round, with ``t`` and
    ``p_value`` None and ``dependent_on`` the others. Returns the inputs kept, in
    their order, and each round's dropped input with its t and p.
    """
    if not 0 < alpha < 1:
        raise InputError(f"significance level {alpha!r}: give a number between 0 and 1 (e.g. 0.05)")
    X, y = check_array(X), np.asarray(y, dtype=float).ravel()
    keep, dropped = list(range(X.shape[1])), []
    offset = int(fit_intercept)
    while len(keep) > 1:
        design = design_matrix(X[:, keep], fit_intercept=fit_intercept)
        dependent = dependent_columns(design[:, offset:], [names[j] for j in keep])
        if dependent:  # no t-test tells their share apart: the last of them goes first
            dropped.append({"name": dependent[-1], "t": None, "p_value": None, "dependent_on": dependent[:-1]})
            del keep[[names[j] for j in keep].index(dependent[-1])]
            continue
        ols = sm.OLS(y, design).fit()
        pvalues = np.asarray(ols.pvalues)[offset:]
        worst = int(np.argmax(pvalues))
        if not pvalues[worst] > alpha:
            break
        t = float(np.asarray(ols.tvalues)[offset + worst])
        dropped.append({"name": names[keep[worst]], "t": t, "p_value": float(pvalues[worst])})
        del keep[worst]
    return {"alpha": alpha, "inputs": [names[j] for j in keep], "dropped": dropped, "candidates": len(names)}


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

    def __init__(self, objective: str = "sae", *, fit_intercept: bool = True):
        super().__init__(p=0, n=0, c=0.0, objective=objective, fit_intercept=fit_intercept, search="exact")

    def fit(self, X, y, progress=None):
        super().fit(X, y, progress=progress)
        X = check_array(X)
        y = np.asarray(y, dtype=float).ravel()
        design = design_matrix(X, fit_intercept=self.fit_intercept)
        with warnings.catch_warnings():  # a dependent design is named in statistics_ instead
            warnings.simplefilter("ignore", SingularMatrixWarning)
            self.ols_ = sm.OLS(y, design).fit()
        names = list(getattr(self, "feature_names_in_", [f"x{i + 1}" for i in range(X.shape[1])]))
        names = (["const"] if self.fit_intercept else []) + [str(n) for n in names]
        self.statistics_ = ols_statistics(self.ols_, names, fit_intercept=self.fit_intercept)
        # R of the design's QR: the leverage of a new row x is |x R^-1|², h = x (XᵀX)^-1 xᵀ
        self.design_r_ = np.linalg.qr(design, mode="r")
        return self

    def prediction_interval(self, X, alpha: float = 0.05) -> np.ndarray:
        """Lower and upper ``1 − alpha`` prediction bounds for new samples, shape (n, 2)."""
        check_is_fitted(self, "ols_")
        design = design_matrix(X, fit_intercept=self.fit_intercept)
        frame = self.ols_.get_prediction(design).summary_frame(alpha=alpha)
        return frame[["obs_ci_lower", "obs_ci_upper"]].to_numpy()

    def leverage(self, X) -> np.ndarray:
        """``h = x (XᵀX)^-1 xᵀ`` of each row (on the modelling rows: the hat matrix's diagonal h_ii)."""
        check_is_fitted(self, "design_r_")
        design = design_matrix(X, fit_intercept=self.fit_intercept)
        return np.sum(solve_triangular(self.design_r_, design.T, trans="T") ** 2, axis=0)

    def mean_interval(self, X, alpha: float = 0.05) -> np.ndarray:
        """Lower and upper ``1 − alpha`` bounds of the mean response, shape (n, 2): ``ŷ ± t·σ·√h``."""
        check_is_fitted(self, "ols_")
        prediction = design_matrix(X, fit_intercept=self.fit_intercept) @ np.asarray(self.ols_.params)
        half = stats.t.ppf(1 - alpha / 2, self.ols_.df_resid) * np.sqrt(self.ols_.scale * self.leverage(X))
        return np.column_stack([prediction - half, prediction + half])
