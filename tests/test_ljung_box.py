"""The Ljung–Box test by FFT autocorrelations equals statsmodels' acorr_ljungbox, which correlates every lag."""

import numpy as np
import pytest
from statsmodels.stats.diagnostic import acorr_ljungbox

from groupfit.metrics import ljung_box


@pytest.mark.parametrize(("n", "phi", "lags"), [(12, 0.0, 10), (500, 0.3, 10), (20000, 0.9, 10), (3000, -0.5, 25)])
def test_q_and_p_equal_statsmodels(n, phi, lags):
    rng = np.random.default_rng(n)
    noise = rng.normal(size=n)
    residual = np.empty(n)
    residual[0] = noise[0]
    for k in range(1, n):
        residual[k] = phi * residual[k - 1] + noise[k]
    residual += 3.0  # a mean the test removes
    test = ljung_box(residual, lags)
    table = acorr_ljungbox(residual, lags=[test["lags"]])
    assert test["Q"] == pytest.approx(float(table["lb_stat"].iloc[0]), rel=1e-9)
    assert test["p_value"] == pytest.approx(float(table["lb_pvalue"].iloc[0]), rel=1e-6, abs=1e-300)
