"""The recalibration tuning refits the model on the first part of a run as the model was fitted: the same ridge
penalty (alpha · m · Σ (β·s)², :mod:`groupfit.models.ridge`), checked against scikit-learn's Ridge."""

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import Ridge

from groupfit.cli import main
from groupfit.model import ModelFile
from groupfit.recalibration_tuning import held_out_series

SENSORS = ["T1", "T2", "T3", "T4"]


def collinear_run(n: int = 1200, seed: int = 3) -> pd.DataFrame:
    """Four sensors that rise together (one warm-up, each with a little of its own), the error on two of them."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 60.0
    common = 5 * (1 - np.exp(-t / 7200.0))
    temps = 20 + common[:, None] * [1.0, 0.9, 1.1, 0.8] + 0.05 * rng.standard_normal((n, 4)).cumsum(axis=0) / 10
    frame = pd.DataFrame(temps, columns=SENSORS)
    frame.insert(0, "time_s", t)
    frame["error_um"] = 3 * temps[:, 0] - 2 * temps[:, 2] + 0.1 * rng.standard_normal(n)
    return frame


def sklearn_ridge(x: np.ndarray, y: np.ndarray, alpha: float):
    """α·m on inputs scaled to unit standard deviation, the intercept free: scikit-learn's Ridge does the rest."""
    scale = x.std(axis=0)
    fitted = Ridge(alpha=alpha * len(x)).fit(x / scale, y)
    return lambda rows: fitted.predict(rows / scale)


@pytest.mark.parametrize("alpha", [0.001, 0.1])
def test_the_held_out_refit_carries_the_models_own_ridge_penalty(tmp_path, alpha):
    frame = collinear_run()
    frame.to_csv(tmp_path / "run.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "run.csv"), "--temps", ",".join(SENSORS), "--p", "0"]
    args += ["--ridge", str(alpha), "--reference", "none", "--recalibrate", "none", "--quiet"]
    assert main([*args, "--out", str(tmp_path / "m")]) == 0
    model = ModelFile.load(tmp_path / "m" / "model.json")
    x, y = frame[SENSORS].to_numpy(), frame["error_um"].to_numpy()
    # the fit's own coefficients are this penalty on the whole run
    whole = sklearn_ridge(x, y, alpha)
    np.testing.assert_allclose(model.predict(x), whole(x), rtol=0, atol=1e-6)
    # the tuning's refit on the first half, predicting the second
    (held,) = held_out_series(model, [(frame, y)], cuts=(0.5,))
    half = len(frame) // 2
    expected = sklearn_ridge(x[:half], y[:half], alpha)(x[half:])
    np.testing.assert_allclose(held.prediction, expected, rtol=0, atol=1e-6)
    np.testing.assert_allclose(held.residual, y[half:] - expected, rtol=0, atol=1e-6)
