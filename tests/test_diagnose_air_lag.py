"""diagnose on a model of rises over the air: a part that lags the air is found over the air, and written on
absolute readings with the same predictions."""

import json

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict
from support import independent_machine as machine
from support.bench_modules import load
from support.grouped_reference import shared_effect_fit

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.augment import augment_model_over_reference
from groupfit.diagnose.problem import stacked_residual
from groupfit.diagnose.residual import model_inputs, predict
from groupfit.features import Feature, lowpass
from groupfit.grouping import serving_group_index
from groupfit.heldout.folds import make_folds
from groupfit.model import model_file_problem
from groupfit.models.grouped import GroupedRegressor
from groupfit.reference import with_reference
from groupfit.runtime import replay_groups

PERIOD = 60.0
TEMPS = ["T1", "T2"]
GAINS = (2.0, -1.5)
LAG_TAU_S = 3600.0


def workshop_run(seed, hours=24.0, ambient_level=20.0, lag_gain=4.0):
    """A machine whose error follows its parts' rises over the air (probe and workpiece in the air).

    T1 and T2 follow the air and the spindle's heat; an unsensed part follows the air with τ = 1 h and adds
    ``lag_gain`` µm per kelvin of its lag behind the air. The air: a 3 K daily swing and an HVAC step.
    """
    rng = np.random.default_rng(seed)
    n = int(hours * 3600 / PERIOD)
    speed = np.repeat(rng.choice([0.0, 2000.0, 4000.0, 6000.0], size=int(hours / 1.5) + 1), 90)[:n]
    heat = (speed / 1000.0) ** (5 / 3)
    time = np.arange(n) * PERIOD
    air = ambient_level + 3.0 * np.sin(2 * np.pi * (time / 86400.0 + rng.uniform()))
    air = air + np.where(time > rng.uniform(0.3, 0.7) * time[-1], rng.uniform(-1.5, 1.5), 0.0)
    parts = [
        air + 0.3 * lowpass(heat, 900.0, PERIOD, before=0.0),
        air + 0.1 * lowpass(heat, 3600.0, PERIOD, before=0.0),
    ]
    frame = pd.DataFrame({"time_s": time, "speed_rpm": speed, "T_amb": np.round(air + rng.normal(0, 0.02, n), 2)})
    for name, part in zip(TEMPS, parts):
        frame[name] = np.round(part + rng.normal(0, 0.02, n), 2)
    lag = lowpass(air, LAG_TAU_S, PERIOD) - air
    frame["error_um"] = sum(g * (p - air) for g, p in zip(GAINS, parts)) + lag_gain * lag + rng.normal(0, 0.05, n)
    return frame


def rises_model(frame, p=0):
    run = load_run(frame, temps=TEMPS, name="modelling")
    referenced = with_reference(run, "T_amb")
    return GroupedRegressor(p=p).fit(referenced.temps, referenced.error).to_model_file(referenced).to_dict(), run


def rises_design(frame, tau_s):
    """[T1 − T_amb, T2 − T_amb, low-pass(T_amb) − T_amb low-passed 2 min]: the model of rises with the air lag,
    as numpy sees it."""
    air = frame["T_amb"].to_numpy(float)
    lag = lowpass(air, tau_s, PERIOD) - lowpass(air, 120.0, PERIOD)
    return np.column_stack([frame[TEMPS].to_numpy(float) - air[:, None], lag])


def test_a_part_lagging_the_air_is_found_over_the_air_and_written_on_absolute_readings():
    modelling, warmer = workshop_run(1), workshop_run(2, ambient_level=23.0)
    model, run = rises_model(modelling)
    validation = load_run(warmer, temps=TEMPS, name="warmer_day")
    result = diagnose(model, run, validation, live_rule=replay_groups)

    first = result.added[0]
    assert first.feature.column == "T_amb" and first.feature.transform == "lowpass" and first.over == "T_amb"
    assert first.feature.tau_s == LAG_TAU_S
    assert "over T_amb" in result.summary().splitlines()[0]
    assert not result.reference.dropped  # the rises were right: the reference stays in what the model computes
    assert result.after["validate"]["rms_um"] < 0.2 * result.before["validate"]["rms_um"]
    assert result.improved is True

    written = result.model.to_dict()
    assert written.get("reference") is None and "T_amb" in written["temps"]
    assert model_file_problem(written) is None

    # the written model is least squares on the rises with the lag over the air, as numpy fits it
    y = modelling["error_um"].to_numpy(float)
    coef, *_ = np.linalg.lstsq(np.c_[np.ones(len(y)), rises_design(modelling, LAG_TAU_S)], y, rcond=None)
    expected = np.c_[np.ones(len(warmer)), rises_design(warmer, LAG_TAU_S)] @ coef
    np.testing.assert_allclose(predict(written, validation), expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(predict(written, validation, replay_groups), expected, rtol=0, atol=1e-9)

    # its held-out score, as scikit-learn scores the rises with and without the lag on the same conditions
    groups = make_folds([modelling], ["speed_rpm"]).labels
    design = rises_design(modelling, LAG_TAU_S)
    without = cross_val_predict(LinearRegression(), design[:, :2], y, groups=groups, cv=LeaveOneGroupOut())
    with_lag = cross_val_predict(LinearRegression(), design, y, groups=groups, cv=LeaveOneGroupOut())
    assert first.score == pytest.approx(1.0 - np.sum((y - with_lag) ** 2) / np.sum((y - without) ** 2), rel=1e-9)

    # the same low-pass taken as read (absolute) was scored too, and explains less
    absolute = [c for c in result.candidates if c.feature == first.feature and c.over is None]
    assert absolute and absolute[0].score < first.score


def test_without_a_lagging_part_nothing_is_added_over_the_air():
    modelling = workshop_run(3, lag_gain=0.0)
    model, run = rises_model(modelling)
    result = diagnose(model, run, live_rule=replay_groups)
    assert not any(c.over for c in result.added)
    assert result.model.reference == "T_amb"


def test_a_grouped_model_keeps_its_breaks_and_the_written_model_predicts_as_its_rises():
    modelling = workshop_run(1)
    model, run = rises_model(modelling, p=2)
    feature = Feature("T_amb", "lowpass", tau_s=LAG_TAU_S)
    written = augment_model_over_reference(model, [run], [model_inputs(model, run)], feature).to_dict()
    assert written["breaks"] == model["breaks"] and written.get("reference") is None
    assert model_file_problem(written) is None

    # the rises fitted with the lag's coefficient shared by the groups, as numpy sees it
    design = rises_design(modelling, LAG_TAU_S)
    own = np.column_stack([np.ones(len(design)), design[:, :-1]])
    y = modelling["error_um"].to_numpy(float)
    (gamma,), coefficients, _ = shared_effect_fit(own, design[:, -1:], y, model["breaks"], model["n"])
    serving = serving_group_index(model["breaks"], len(y), model["n"])
    expected = np.einsum("ij,ij->i", own, np.asarray(coefficients)[serving]) + gamma * design[:, -1]
    np.testing.assert_allclose(predict(written, run), expected, rtol=0, atol=1e-9)
    # on the controller: the groups the run-time rule picks, with the same coefficients
    replayed = stacked_residual(written, [run], replay_groups)
    assert np.all(np.isfinite(replayed))
    assert np.sqrt(np.mean(replayed**2)) < 0.2


def test_the_cli_names_the_lag_over_the_air_and_the_written_model_replays(tmp_path, capsys, fitted_on_monday):
    data, other, model_path = fitted_on_monday(workshop_run(1), workshop_run(2, ambient_level=23.0), TEMPS)
    capsys.readouterr()
    args = ["diagnose", str(model_path), "--data", str(data), "--validate", str(other), "--out", str(tmp_path / "d")]
    assert main([*args, "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    added = result["added"][0]
    assert added["column"] == "T_amb" and added["over_reference"] == "T_amb"
    assert added["description"].endswith("over T_amb") and result["improved"] is True
    written = tmp_path / "d" / "model_augmented.json"
    assert main(["replay", str(written), "--data", str(other), "--json", "-"]) == 0
    replayed = np.array([s["residual_um"] for s in json.loads(capsys.readouterr().out)["samples"]])
    assert np.sqrt(np.mean(replayed**2)) == pytest.approx(result["after"]["validate"]["rms_um"], rel=1e-12)


def test_the_written_model_runs_on_the_controller_as_in_python(drivers):
    from support.replay import assert_same_decisions, python_replay

    from groupfit.export.harness import run_driver
    from groupfit.runtime import RuleTables

    modelling = workshop_run(1)
    model, run = rises_model(modelling, p=2)
    feature = Feature("T_amb", "lowpass", tau_s=LAG_TAU_S)
    written = augment_model_over_reference(model, [run], [model_inputs(model, run)], feature).to_dict()
    readings = modelling[list(RuleTables.from_model(written).raw_names)].to_numpy(float)
    assert list(RuleTables.from_model(written).raw_names) == [*TEMPS, "T_amb"]  # the air read once, for both inputs
    warmer = workshop_run(2, ambient_level=23.0)[[*TEMPS, "T_amb"]].to_numpy(float)
    for precision in ("double", "single"):
        outputs = run_driver(drivers(f"air lag {precision}", written, precision), [readings, warmer])
        for temps, c_out in zip([readings, warmer], outputs):
            assert_same_decisions(c_out, python_replay(written, temps, precision))


def test_the_lag_is_taken_over_the_air_low_passed_for_a_few_minutes_not_over_each_noisy_reading():
    # run r7020 of the independent machine (bench/independent_machine.py), its error on the parts' rises over
    # the air, the unsensed thin part behind the air missing. Over each reading of the air the lag improves
    # only half of the held-out conditions and is refused; over the air low-passed 2 min it improves more.
    bench = load("bench_diagnose_independent")
    scenario = machine.random_scenarios(1, first_seed=7020, truth="rises")[0]
    model, modelling, validation = bench.base_model(scenario, "default")
    result = diagnose(model, modelling, validation, live_rule=replay_groups)
    first = result.added[0]
    assert first.feature.column == "T_amb" and first.over == "T_amb"
    assert result.after["validate"]["rms_um"] < 0.6 * result.before["validate"]["rms_um"]

    # the held-out conditions as scikit-learn scores them, with the lag over the air as read and low-passed
    frame, y = modelling.frame, modelling.error
    period = model["sampling_period_s"]
    groups = make_folds([frame], ["spindle_rpm"]).labels
    air = frame["T_amb"].to_numpy(float)
    rises = frame[scenario.temps].to_numpy(float) - air[:, None]
    lag = first.feature.compute(air, period)

    def fold_sse(design):
        predicted = cross_val_predict(LinearRegression(), design, y, groups=groups, cv=LeaveOneGroupOut())
        return np.array([np.sum((y - predicted)[groups == g] ** 2) for g in np.unique(groups)])

    base = fold_sse(rises)
    over_reading = fold_sse(np.c_[rises, lag - air])
    over_steady = fold_sse(np.c_[rises, lag - lowpass(air, 120.0, period)])
    n_folds = len(base)
    assert np.count_nonzero(over_reading < base) <= n_folds / 2 < np.count_nonzero(over_steady < base)
    assert first.score == pytest.approx(1 - over_steady.sum() / base.sum(), rel=1e-9)
