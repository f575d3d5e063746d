"""The reference check with the effects in: diagnose on rises over T_amb and on absolute readings, keep the better.

Runs from the independent lumped machine (``bench/independent_machine.py``,
no code shared with groupfit's simulators), fitted as ``groupfit fit`` does by
default: the sensors as rises over ``T_amb``.
"""

import numpy as np
import pytest
from bench_modules import load
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict

from groupfit.diagnose import diagnose
from groupfit.diagnose.folds import make_folds
from groupfit.diagnose.loop import MIN_SCORE
from groupfit.features import derived_matrix
from groupfit.runtime import replay_groups

machine = load("independent_machine")
bench = load("bench_diagnose_independent")


def held_out_rms(design, y, groups):
    predicted = cross_val_predict(LinearRegression(), design, y, groups=groups, cv=LeaveOneGroupOut())
    return float(np.sqrt(np.mean((y - predicted) ** 2)))


def diagnosed(seed, truth):
    scenario = machine.random_scenarios(1, first_seed=seed, truth=truth)[0]
    model, modelling, validation = bench.base_model(scenario, "default")
    return scenario, model, modelling, diagnose(model, modelling, validation, live_rule=replay_groups)


def test_a_pump_the_wrong_reference_hid_is_found_on_absolute_readings():
    # a pump heats a part no sensor sees; the error follows absolute temperatures. On rises over T_amb
    # neither reading wins before the effect is in, and with the reference kept no pump candidate passes.
    scenario, model, modelling, result = diagnosed(26, "absolute")
    check = result.reference
    branch = check["branch"]
    assert check["dropped"] and result.model.get("reference") is None
    assert branch["effects"]["given"] == [] and branch["reason"] is None
    assert [c.feature.column for c in result.added][:1] == ["pump_on"]
    assert branch["effects"]["absolute"] == [c.feature.name for c in result.added]
    assert result.after["validate"]["rms_um"] < 0.6 * result.before["validate"]["rms_um"]
    assert result.improved is True
    assert result.summary().splitlines()[0].startswith("reference dropped: the error follows the absolute")

    # both end models' held-out RMS as scikit-learn scores them on the same conditions
    frame = modelling.frame
    y = modelling.error
    groups = make_folds([frame], ["spindle_rpm", "pump_on"]).labels
    absolute = frame[scenario.temps].to_numpy(float)
    rises = absolute - frame[["T_amb"]].to_numpy(float)
    effects = derived_matrix([c.feature for c in result.added], frame, model["sampling_period_s"])
    rms = branch["held_out_rms_um"]
    assert rms["given"] == pytest.approx(held_out_rms(rises, y, groups), rel=1e-9)
    assert rms["absolute"] == pytest.approx(held_out_rms(np.c_[absolute, effects], y, groups), rel=1e-9)
    assert rms["absolute"] < 0.5 * rms["given"]


def test_a_branch_that_needs_the_air_itself_keeps_the_reference():
    # the error follows rises over the air and a part that lags the air: on absolute readings a short
    # low-pass of T_amb wins the held-out folds, but it only gives the air a free weight
    _, _, _, result = diagnosed(10, "rises")
    branch = result.reference["branch"]
    assert branch["effects"]["absolute"] and all(e.startswith("T_amb") for e in branch["effects"]["absolute"][:1])
    assert branch["score"] >= MIN_SCORE and branch["folds_improved"] == result.reference["n_folds"]
    assert "`T_amb` itself" in branch["reason"]
    assert not result.reference["dropped"] and result.model["reference"] == "T_amb"
