"""Error metrics and the whiteness test of a residual series (µm)."""

from __future__ import annotations

import numpy as np


def error_metrics(residuals: np.ndarray) -> dict[str, float]:
    """R (sum of |e|), RMS and max |e| of a residual series, in µm."""
    residuals = np.asarray(residuals, dtype=float)
    return {
        "R_um": float(np.sum(np.abs(residuals))),
        "rms_um": float(np.sqrt(np.mean(residuals**2))),
        "max_um": float(np.max(np.abs(residuals))),
    }


def ljung_box(residual: np.ndarray, lags: int = 10) -> dict[str, float]:
    """Ljung–Box Q of the residual's autocorrelations up to ``lags`` (statsmodels); white when p is large."""
    from statsmodels.stats.diagnostic import acorr_ljungbox

    table = acorr_ljungbox(np.asarray(residual, dtype=float), lags=[lags])
    return {"lags": lags, "Q": float(table["lb_stat"].iloc[0]), "p_value": float(table["lb_pvalue"].iloc[0])}
