import numpy as np
import pandas as pd
import pytest

from groupfit.errors import InputError
from groupfit.features import Feature, derived_matrix, lowpass


def test_lowpass_of_a_step_is_the_first_order_response_at_the_samples():
    period, tau = 100.0, 1800.0
    x = np.r_[0.0, np.ones(200)]
    y = lowpass(x, tau, period)
    k = np.arange(len(x))
    # zero-order-hold discretisation of tau·dy/dt = x - y: exact at the samples
    np.testing.assert_allclose(y[1:], 1.0 - np.exp(-k[1:] * period / tau), rtol=1e-12)
    assert y[0] == 0.0


def test_lowpass_starts_in_equilibrium_with_the_first_value():
    y = lowpass(np.full(50, 21.5), 3600.0, 100.0)
    np.testing.assert_allclose(y, 21.5)


def test_derivative_delay_identity():
    x = np.array([1.0, 2.0, 4.0, 7.0])
    np.testing.assert_allclose(Feature("x", "derivative").compute(x, 1800.0), [0.0, 2.0, 4.0, 6.0])
    np.testing.assert_allclose(Feature("x", "delay", delay_samples=2).compute(x, 100.0), [1.0, 1.0, 1.0, 2.0])
    np.testing.assert_allclose(Feature("x").compute(x, 100.0), x)


def test_names_round_trip_and_validation():
    feature = Feature("T_amb", "lowpass", tau_s=7200.0)
    assert feature.name == "T_amb~lp7200s" and feature.describe() == "low-pass τ = 2 h"
    assert Feature.from_dict(feature.to_dict()) == feature
    with pytest.raises(InputError, match="tau_s"):
        Feature("T_amb", "lowpass")
    with pytest.raises(InputError, match="choose one of"):
        Feature("T_amb", "smooth")


def test_derived_matrix_names_the_run_the_missing_column_and_the_columns_it_has():
    frame = pd.DataFrame({"a": [1.0, 2.0]})
    message = r"^val\.csv: column 'b' not found; the model computes its input b~lp60s from it\. The columns are: a$"
    with pytest.raises(InputError, match=message):
        derived_matrix([Feature("b", "lowpass", tau_s=60.0)], frame, 100.0, "val.csv")


def test_on_time_is_the_value_times_the_hours_on_without_a_break():
    rng = np.random.default_rng(4)
    speed = np.repeat(rng.choice([0.0, 0.0, 1500.0, 3000.0, 4500.0], size=60), rng.integers(1, 9, size=60))
    period = 30.0
    hours, hours_on = 0.0, []
    for value in speed:  # the controller's count, one sample at a time
        hours = hours + period / 3600.0 if value != 0 else 0.0
        hours_on.append(hours)
    on_time = Feature("n", "ontime", start="rest")
    np.testing.assert_allclose(on_time.compute(speed, period), speed * hours_on, rtol=1e-12, atol=0.0)
    heat = Feature("n", "ontime", start="rest", exponent=5 / 3, scale=1000.0)
    np.testing.assert_allclose(heat.compute(speed, period), (speed / 1000.0) ** (5 / 3) * hours_on, rtol=1e-12)
    assert on_time.name == "n~ontime" and heat.describe() == "heat law (x/1000)^1.67, times the hours on"
    assert Feature.from_dict(heat.to_dict()) == heat
    with pytest.raises(InputError, match="starts from rest"):
        Feature("n", "ontime")
