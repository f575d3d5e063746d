"""What is left in a residual: whiteness and drift."""

from __future__ import annotations

import numpy as np

from groupfit.metrics import ljung_box

__all__ = ["drift", "ljung_box"]


def drift(residual: np.ndarray, time_s: np.ndarray) -> dict[str, float]:
    """Linear trend of the residual in µm per hour, with a Newey–West (HAC) t-test."""
    import statsmodels.api as sm

    hours = (np.asarray(time_s, dtype=float) - time_s[0]) / 3600.0
    lags = int(np.ceil(4 * (len(hours) / 100.0) ** (2 / 9)))
    fit = sm.OLS(np.asarray(residual, dtype=float), sm.add_constant(hours)).fit(
        cov_type="HAC", cov_kwds={"maxlags": lags}
    )
    return {"slope_um_per_h": float(fit.params[1]), "t": float(fit.tvalues[1]), "p_value": float(fit.pvalues[1])}
