"""diagnose checks the model's reference sensor: rises over T_amb against absolute readings, on held-out conditions."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.policy import REFERENCE_STEADY
from groupfit.diagnose.problem import stacked_residual
from groupfit.diagnose.reference import absolute_model
from groupfit.features import derived_matrix, lowpass
from groupfit.heldout.folds import make_folds
from groupfit.model import model_file_problem
from groupfit.models.grouped import GroupedRegressor
from groupfit.reference import with_reference
from groupfit.runtime import replay_groups

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
PERIOD = 60.0
TEMPS = ["T1", "T2"]
GAINS = (2.0, -1.5)


def workshop_run(seed, hours=24.0, ambient_level=20.0, ambient_swing=2.0, truth="absolute"):
    """Speed steps; T1 (bearings) and T2 (column) follow their heat and the air; T_amb the air.

    ``truth="absolute"``: the error follows the parts' temperatures over a fixed 20 °C (a probe against a
    fixed reference); ``"rises"``: their rises over the air (probe and workpiece in the air). Either way a
    part no sensor sees adds the heat law (n/1000)^(5/3) low-passed with τ = 1.5 h.
    """
    rng = np.random.default_rng(seed)
    n = int(hours * 3600 / PERIOD)
    speed = np.repeat(rng.choice([0.0, 2000.0, 4000.0, 6000.0], size=int(hours / 1.5) + 1), 90)[:n]
    heat = (speed / 1000.0) ** (5 / 3)
    time = np.arange(n) * PERIOD
    air = ambient_level + ambient_swing * np.sin(2 * np.pi * (time / 86400.0 + rng.uniform()))
    air = air + np.where(time > rng.uniform(0.3, 0.7) * time[-1], rng.uniform(-1.0, 1.0), 0.0)
    parts = [
        lowpass(air, 1800.0, PERIOD) + 0.3 * lowpass(heat, 900.0, PERIOD, before=0.0),
        lowpass(air, 7200.0, PERIOD) + 0.1 * lowpass(heat, 3600.0, PERIOD, before=0.0),
    ]
    frame = pd.DataFrame({"time_s": time, "speed_rpm": speed, "T_amb": np.round(air + rng.normal(0, 0.02, n), 2)})
    for name, part in zip(TEMPS, parts):
        frame[name] = np.round(part + rng.normal(0, 0.02, n), 2)
    base = air if truth == "rises" else 20.0
    error = sum(g * (part - base) for g, part in zip(GAINS, parts))
    frame["error_um"] = error + 1.2 * lowpass(heat, 5400.0, PERIOD, before=0.0) + rng.normal(0, 0.05, n)
    return frame


def fitted(frame, reference="T_amb"):
    run = load_run(frame, temps=TEMPS, name="modelling")
    referenced = with_reference(run, reference)
    return GroupedRegressor(p=0).fit(referenced.temps, referenced.error).to_model_file(referenced).to_dict(), run


def rms(values) -> float:
    return float(np.sqrt(np.mean(np.asarray(values)[np.isfinite(values)] ** 2)))


def held_out_rms(design, y, groups):
    predicted = cross_val_predict(LinearRegression(), design, y, groups=groups, cv=LeaveOneGroupOut())
    return float(np.sqrt(np.mean((y - predicted) ** 2)))


def test_a_machine_that_feels_absolute_temperatures_loses_its_reference_and_then_gets_its_effect():
    modelling = workshop_run(1)
    validation = load_run(workshop_run(2, ambient_level=23.0), temps=TEMPS, name="warmer_day")
    model, run = fitted(modelling)
    result = diagnose(model, run, validation, live_rule=replay_groups)

    check = result.reference
    assert check.dropped and check.reference == "T_amb" and result.model.reference is None
    assert result.added and result.added[0].feature.column == "speed_rpm"
    assert result.after["validate"]["rms_um"] < 0.6 * result.before["validate"]["rms_um"]
    assert result.improved is True

    # the held-out RMS of both readings, as scikit-learn scores them on the same conditions
    groups = make_folds([modelling], ["speed_rpm"]).labels
    features = [c.feature for c in result.added[: check.after_effects]]
    effects = derived_matrix(features, modelling, PERIOD)
    absolute = modelling[TEMPS].to_numpy(float)
    rises = absolute - modelling[["T_amb"]].to_numpy(float)
    y = modelling["error_um"].to_numpy(float)
    assert check.held_out_rms_um["given"] == pytest.approx(held_out_rms(np.c_[rises, effects], y, groups), rel=1e-9)
    assert check.held_out_rms_um["absolute"] == pytest.approx(
        held_out_rms(np.c_[absolute, effects], y, groups), rel=1e-9
    )
    assert check.held_out_rms_um["absolute"] < check.held_out_rms_um["given"]


def test_a_machine_that_feels_rises_over_the_air_keeps_its_reference():
    modelling = workshop_run(3, truth="rises")
    validation = load_run(workshop_run(4, ambient_level=23.0, truth="rises"), temps=TEMPS, name="warmer_day")
    model, run = fitted(modelling)
    result = diagnose(model, run, validation, live_rule=replay_groups)
    assert not result.reference.dropped and result.model.reference == "T_amb"
    assert result.added and result.added[0].feature.column == "speed_rpm"
    assert result.after["validate"]["rms_um"] < 0.6 * result.before["validate"]["rms_um"]


def test_a_run_whose_air_stays_still_cannot_tell_and_keeps_the_reference():
    modelling = workshop_run(5, ambient_swing=0.0)
    modelling["T_amb"] = 20.0  # one reading all day: rises and absolute readings differ by a constant
    model, run = fitted(modelling)
    result = diagnose(model, run, live_rule=replay_groups)
    check = result.reference
    assert not check.dropped and check.score == pytest.approx(0.0, abs=1e-6)
    assert result.model.reference == "T_amb"


def test_an_air_reading_steady_within_its_noise_keeps_the_reference_for_a_day_at_another_level():
    # the FE modelling run's air stays at 20 °C within its reading noise; absolute readings shed that noise and
    # win on its held-out folds, yet the repeat of the same programme at 25 °C shows what they would cost
    modelling = load_run(DATASETS / "paper_cycle.csv", temps=TEMPS)
    warmer_day = load_run(DATASETS / "repeat_ambient25.csv", temps=TEMPS)
    model, run = fitted(modelling.frame)
    result = diagnose(model, run, live_rule=replay_groups)
    check = result.reference
    assert check.rule_id == REFERENCE_STEADY and not check.dropped
    assert check.held_out_rms_um["absolute"] < check.held_out_rms_um["given"]  # the folds alone would drop it
    assert result.model.reference == "T_amb" and result.added
    on_model_day = stacked_residual(result.model, [run], replay_groups)
    on_warmer_day = stacked_residual(result.model, [warmer_day], replay_groups)
    on_absolute, _ = absolute_model(result.model, [run])  # what dropping it would do there
    assert rms(on_warmer_day) < 2 * rms(on_model_day)
    assert rms(stacked_residual(on_absolute, [warmer_day], replay_groups)) > 10 * rms(on_warmer_day)


def test_models_without_a_reference_sensor_are_not_checked():
    modelling = workshop_run(6)
    model, run = fitted(modelling, reference=None)
    assert diagnose(model, run, live_rule=replay_groups).reference is None
    model, run = fitted(modelling, reference="start")
    assert diagnose(model, run, live_rule=replay_groups).reference is None


def test_the_cli_reports_the_dropped_reference_and_keep_reference_turns_the_check_off(
    tmp_path, capsys, fitted_on_monday
):
    data, other, model_path = fitted_on_monday(workshop_run(1), workshop_run(2, ambient_level=23.0), TEMPS)
    assert json.loads(model_path.read_text())["reference"] == "T_amb"  # the fit's default on a run with T_amb
    capsys.readouterr()
    args = ["diagnose", str(model_path), "--data", str(data), "--validate", str(other)]
    assert main([*args, "--out", str(tmp_path / "d")]) == 0
    report = capsys.readouterr().out
    assert "reference dropped" in report
    assert "the error follows the absolute temperatures, not their rises over `T_amb`" in report
    assert main([*args, "--out", str(tmp_path / "d"), "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["reference"]["dropped"] and result["improved"] is True
    written = tmp_path / "d" / "model_augmented.json"
    assert json.loads(written.read_text()).get("reference") is None
    assert main(["replay", str(written), "--data", str(other), "--json", "-"]) == 0
    replayed = np.array([s["residual_um"] for s in json.loads(capsys.readouterr().out)["samples"]])
    assert np.sqrt(np.mean(replayed**2)) == pytest.approx(result["after"]["validate"]["rms_um"], rel=1e-12)

    capsys.readouterr()
    assert main([*args, "--keep-reference", "--out", str(tmp_path / "k"), "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["reference"] is None
    assert json.loads((tmp_path / "k" / "model_augmented.json").read_text())["reference"] == "T_amb"


def test_a_grouped_model_loses_its_reference_with_its_breaks_kept_and_still_replays():
    modelling = workshop_run(2)
    run = load_run(modelling, temps=TEMPS, name="modelling")
    referenced = with_reference(run, "T_amb")
    model = GroupedRegressor(p=2).fit(referenced.temps, referenced.error).to_model_file(referenced).to_dict()
    validation = load_run(workshop_run(3, ambient_level=23.0), temps=TEMPS, name="warmer_day")
    result = diagnose(model, run, validation, live_rule=replay_groups)
    assert result.reference.dropped and result.model.reference is None
    assert list(result.model.breaks) == model["breaks"]
    assert result.after["validate"]["rms_um"] < 0.6 * result.before["validate"]["rms_um"]
    assert model_file_problem(result.model.to_dict()) is None
    replayed = stacked_residual(result.model, [validation], replay_groups)
    np.testing.assert_allclose(replayed, result.residuals_after["validate"], rtol=0, atol=1e-12)
