"""Prediction intervals of grouped models (per-group OLS, the serving group's interval)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm

from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.models import MLR, GroupedRegressor

ROOT = Path(__file__).resolve().parents[1]
FRAME = pd.read_csv(ROOT / "datasets" / "paper_cycle.csv")
TEMPS = FRAME[["T1", "T2"]].to_numpy()
ERROR = FRAME["error_um"].to_numpy()
ERROR_NOISE_UM = 0.3
TEMP_NOISE_K = 0.02


def noisy_repeat(seed):
    """The FE modelling cycle as a sensor would record it: seeded white noise on the error and the temperatures."""
    rng = np.random.default_rng(seed)
    temps = TEMPS + rng.normal(scale=TEMP_NOISE_K, size=TEMPS.shape)
    return temps, ERROR + rng.normal(scale=ERROR_NOISE_UM, size=ERROR.shape)


@pytest.mark.parametrize("repeat", [0, 1, 2])
def test_band_covers_about_95_percent_of_a_noisy_repeat(repeat):
    """Fit on one noisy recording of the cycle, check the 95 % band on an independent one."""
    X_fit, y_fit = noisy_repeat(100 + 2 * repeat)
    X_new, y_new = noisy_repeat(101 + 2 * repeat)
    model = GroupedRegressor(p=3, n=3, objective="sse", search="exact").fit(X_fit, y_fit)
    prediction, lower, upper = model.predict(X_new, return_interval=True)
    assert np.array_equal(prediction, model.predict(X_new))
    coverage = np.mean((y_new >= lower) & (y_new <= upper))
    assert 0.90 <= coverage <= 0.99


def test_mlr_interval_is_statsmodels_obs_ci():
    X, y = noisy_repeat(7)
    mlr = MLR().fit(X, y)
    _, lower, upper = mlr.predict(X[:50], return_interval=True, alpha=0.1)
    frame = sm.OLS(y, sm.add_constant(X)).fit().get_prediction(sm.add_constant(X[:50])).summary_frame(alpha=0.1)
    np.testing.assert_allclose(lower, frame["obs_ci_lower"], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(upper, frame["obs_ci_upper"], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(np.column_stack([lower, upper]), mlr.prediction_interval(X[:50], alpha=0.1))


def test_each_sample_gets_the_interval_of_the_group_that_serves_it():
    X, y = noisy_repeat(3)
    model = GroupedRegressor(n=3, fixed_breaks=[45, 100], objective="sse").fit(X, y)
    _, lower, upper = model.predict(X, return_interval=True, level=0.9)
    serving = model.serving_groups()
    for sample in (10, 43, 44, 98, 300):  # 43 and 44 lie in the overlap of groups 1 and 2: group 2 serves them
        g = serving[sample - 1]
        first, last = model.soft_groups_[g]
        design = sm.add_constant(X[first - 1 : last])
        fit = sm.OLS(y[first - 1 : last], design).fit()
        row = np.r_[1.0, X[sample - 1]][None, :]
        frame = fit.get_prediction(row).summary_frame(alpha=0.1)
        assert lower[sample - 1] == pytest.approx(frame["obs_ci_lower"].iloc[0], abs=1e-8)
        assert upper[sample - 1] == pytest.approx(frame["obs_ci_upper"].iloc[0], abs=1e-8)
    assert serving[42] == 1 and serving[43] == 1 and serving[41] == 0


def test_level_and_alpha():
    X, y = noisy_repeat(5)
    model = GroupedRegressor(n=0, fixed_breaks=[60], objective="sse").fit(X, y)
    _, lo90, hi90 = model.predict(X, return_interval=True, level=0.9)
    _, lo_a, hi_a = model.predict(X, return_interval=True, alpha=0.1)
    _, lo99, hi99 = model.predict(X, return_interval=True, level=0.99)
    np.testing.assert_array_equal(lo90, lo_a)
    assert np.all(hi99 - lo99 > hi90 - lo90)
    with pytest.raises(InputError, match="disagree"):
        model.predict(X, return_interval=True, level=0.9, alpha=0.05)
    with pytest.raises(InputError, match="between 0 and 1"):
        model.predict(X, return_interval=True, level=1.5)


def test_model_loaded_from_a_file_has_no_interval_statistics():
    X, y = noisy_repeat(9)
    model = GroupedRegressor(n=3, fixed_breaks=[45], objective="sse").fit(X, y)
    frame = pd.DataFrame({"time_s": FRAME["time_s"], "T1": X[:, 0], "T2": X[:, 1], "error_um": y})
    run = load_run(frame, temps=["T1", "T2"], name="noisy")
    loaded = GroupedRegressor.from_model_file(model.to_model_file(run).to_dict())
    np.testing.assert_allclose(loaded.predict(X), model.predict(X))
    with pytest.raises(InputError, match="refit"):
        loaded.predict(X, return_interval=True)
