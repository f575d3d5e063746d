"""``groupfit replay``: the rule sample by sample over a recorded run, as JSON and a figure."""

import json

import numpy as np
import pandas as pd
import pytest
from support import write_model
from test_switching_models import (
    DIAG_AMBIENT,
    DIAG_SOURCE,
    SYNTHETIC,
    augmented_model,
    augmented_validation,
    eight_sensor_model,
    eight_sensor_validation,
    fe_model,
    fe_validation_runs,
    heat_law_runs,
    synthetic_model,
)

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.runtime import FAULT_HELD, FAULT_SENSOR, SwitchingRule, replay_groups


@pytest.fixture()
def model_path(tmp_path):
    model, _ = synthetic_model()
    path = tmp_path / "model.json"
    write_model(model, path)
    return path


def replay(*args):
    return main(["replay", *map(str, args)])


def test_replay_json_has_the_spec_shape_and_the_residuals(tmp_path, model_path, capsys):
    out = tmp_path / "fig"
    assert replay(model_path, "--data", SYNTHETIC, "--json", tmp_path / "r.json", "--out", out) == 0
    report = capsys.readouterr().out
    result = json.loads((tmp_path / "r.json").read_text())
    frame = pd.read_csv(SYNTHETIC)
    assert len(result["samples"]) == len(frame)
    first = result["samples"][0]
    assert {"i", "group", "prediction_um", "fault"} <= set(first) and first["i"] == 1
    assert {"residual_um", "compensation_um", "switch", "time_s"} <= set(first)
    residual = np.array([s["residual_um"] for s in result["samples"]])
    prediction = np.array([s["prediction_um"] for s in result["samples"]])
    assert np.allclose(residual, frame["error_um"] - prediction, atol=1e-12)
    assert result["rms_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-12)
    model = json.loads(model_path.read_text())
    # the modelling run itself: the offline grouping, with the bumpless transfer over n samples at each switch
    coefficients = np.asarray(model["coefficients"])
    groups = np.asarray([s["group"] for s in result["samples"]]) - 1
    temps = frame[model["temps"]].to_numpy()
    offline = coefficients[groups, 0] + np.einsum("ij,ij->i", temps, coefficients[groups, 1:])
    for switch in np.flatnonzero(np.diff(groups)) + 1:  # at sample k, (n+1-k)/(n+1) of the gap from the last output
        gap = offline[switch - 1] - offline[switch]
        for k in range(1, model["n"] + 1):
            offline[switch + k - 1] += (model["n"] + 1 - k) / (model["n"] + 1) * gap
    assert np.max(np.abs(prediction - offline)) < 1e-9
    hard = coefficients[groups, 0] + np.einsum("ij,ij->i", temps, coefficients[groups, 1:])
    assert np.sqrt(np.mean((frame["error_um"] - hard) ** 2)) == pytest.approx(model["training"]["rms_um"], rel=1e-9)
    assert result["offline_breaks"] == model["breaks"] and result["samples_off_offline_group"] == 0
    assert [s["i"] for s in result["switches"]] == [w[0] for w in model["switching"]["windows"]]
    assert (out / "replay.png").stat().st_size > 10_000
    assert "switches" in report and "residual RMS" in report


def test_nonfinite_readings_are_sensor_faults_not_errors(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    frame.loc[10:11, "T2"] = np.nan  # two samples: held
    frame.loc[50:55, "T1"] = np.inf  # six samples: held three, then fault
    frame.loc[80, "error_um"] = np.nan  # a missing error: no residual there
    data = tmp_path / "faulty.csv"
    frame.to_csv(data, index=False)
    assert replay(model_path, "--data", data, "--json", tmp_path / "r.json") == 0
    result = json.loads((tmp_path / "r.json").read_text())
    faults = [s["fault"] for s in result["samples"]]
    assert faults[10:12] == [FAULT_HELD, FAULT_HELD]
    assert faults[50:56] == [FAULT_HELD] * 3 + [FAULT_SENSOR] * 3 and faults[56] == 0
    assert all(s["residual_um"] is None for s in result["samples"][53:56])
    assert result["samples"][80]["residual_um"] is None
    assert result["scored_samples"] == len(frame) - 4
    assert result["faults"] == {"held_samples": 5, "sensor_fault_samples": 3}
    assert result["nonfinite_readings"] == 8


def test_a_sensor_stuck_for_the_whole_run_is_replayed_as_the_controller_reads_it(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC).assign(T2=21.5)  # stuck at one value: the rule gets what it would read
    data = tmp_path / "stuck.csv"
    frame.to_csv(data, index=False)
    assert replay(model_path, "--data", data, "--json", tmp_path / "r.json") == 0
    result = json.loads((tmp_path / "r.json").read_text())
    rule = SwitchingRule(ModelFile.load(model_path), period_s=float(frame["time_s"].diff().iloc[1]))
    expected = rule.replay(frame[list(ModelFile.load(model_path).temps)].to_numpy(dtype=float)).prediction_um
    np.testing.assert_array_equal([s["prediction_um"] for s in result["samples"]], expected)
    with pytest.raises(InputError, match="'T2' is constant"):  # fitting on it is refused, as before
        load_run(data, temps=["T1", "T2"])


def test_run_without_error_column_has_null_residuals(tmp_path, model_path, capsys):
    data = tmp_path / "no_error.csv"
    pd.read_csv(SYNTHETIC).drop(columns="error_um").to_csv(data, index=False)
    assert replay(model_path, "--data", data, "--json", "-") == 0
    result = json.loads(capsys.readouterr().out)
    assert result["rms_um"] is None and all(sample["residual_um"] is None for sample in result["samples"])


def test_other_sampling_period_is_refused_with_one_line(tmp_path, model_path, capsys):
    frame = pd.read_csv(SYNTHETIC)
    frame["time_s"] = frame["time_s"] * 0.6
    data = tmp_path / "fast.csv"
    frame.to_csv(data, index=False)
    assert replay(model_path, "--data", data, "--json", tmp_path / "r.json", "--out", tmp_path / "fig") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fast.csv" in err[0] and "sampling period 60 s differs from the model's 100 s" in err[0]
    assert not (tmp_path / "r.json").exists() and not (tmp_path / "fig").exists()
    assert "--resample 100" in err[0]  # the advice, followed, replays the run
    assert replay(model_path, "--data", data, "--resample", "100", "--json", tmp_path / "r.json") == 0
    assert json.loads((tmp_path / "r.json").read_text())["sampling_period_s"] == 100.0
    frame.assign(time_s=frame["time_s"] / 0.6 * 1.5).to_csv(data, index=False)  # slower than the model: refit
    assert replay(model_path, "--data", data) == 2
    assert "fit a model at this period" in capsys.readouterr().err


def test_missing_temperature_column_is_refused(tmp_path, model_path, capsys):
    data = tmp_path / "short.csv"
    pd.read_csv(SYNTHETIC).drop(columns="T3").to_csv(data, index=False)
    assert replay(model_path, "--data", data) == 2
    assert "column 'T3' not found" in capsys.readouterr().err


def test_missing_model_file_is_refused(tmp_path, capsys):
    assert replay(tmp_path / "none.json", "--data", SYNTHETIC) == 2
    assert "model file not found" in capsys.readouterr().err


def test_compensation_in_controller_counts_when_asked(tmp_path, model_path):
    assert replay(model_path, "--data", SYNTHETIC, "--resolution-um", "0.1", "--json", tmp_path / "r.json") == 0
    samples = json.loads((tmp_path / "r.json").read_text())["samples"]
    for s in samples[:50]:
        magnitude = int(np.floor(abs(s["compensation_um"]) * 10 + 0.5))
        assert s["compensation_counts"] == magnitude * np.sign(s["compensation_um"])


def test_single_precision_replay(tmp_path, model_path):
    assert replay(model_path, "--data", SYNTHETIC, "--precision", "single", "--json", tmp_path / "r.json") == 0
    result = json.loads((tmp_path / "r.json").read_text())
    predictions = [s["prediction_um"] for s in result["samples"]]
    assert predictions == [float(np.float32(v)) for v in predictions]


def test_other_duty_cycle_on_the_eight_sensor_model(tmp_path):
    model, _ = eight_sensor_model()
    write_model(model, tmp_path / "model.json")
    run = eight_sensor_validation()
    run.frame.to_csv(tmp_path / "other.csv", index=False)
    assert replay(tmp_path / "model.json", "--data", tmp_path / "other.csv", "--json", tmp_path / "r.json") == 0
    result = json.loads((tmp_path / "r.json").read_text())
    assert [s["to"] for s in result["switches"]] == list(range(2, 8))
    for s, (first, last) in zip(result["switches"], result["windows"]):
        assert first <= s["i"] <= last
    expected = SwitchingRule(model).replay(run.temps)
    assert [s["group"] for s in result["samples"]] == expected.group.tolist()
    assert result["rms_um"] is not None and result["faults"]["sensor_fault_samples"] == 0


def test_fe_validation_runs_replay(tmp_path):
    model, run = fe_model()
    write_model(model, tmp_path / "model.json")
    runs = fe_validation_runs(model)
    if not runs:
        pytest.skip("no FE validation data set in datasets/")
    for validation in runs:
        target = tmp_path / f"{validation.name}.json"
        assert replay(tmp_path / "model.json", "--data", validation.source, "--json", target) == 0
        result = json.loads(target.read_text())
        assert len(result["samples"]) == validation.n_samples and result["rms_um"] > 0
        assert [s["to"] for s in result["switches"]] == list(range(2, model["p"] + 2))


# derived inputs ---------------------------------------------------------------


@pytest.mark.parametrize(
    "label, which",
    [
        ("lowpass p=0", "modelling"),
        ("lowpass p=0", "validation"),
        ("all kinds p=2", "modelling"),
        ("on/off p=1", "validation"),
    ],
)
def test_models_with_derived_inputs_replay_from_the_source_columns(tmp_path, label, which):
    model, run = augmented_model(label)
    data = run if which == "modelling" else augmented_validation(label)
    write_model(model, tmp_path / "model.json")
    assert replay(tmp_path / "model.json", "--data", data.source, "--json", tmp_path / "r.json") == 0
    result = json.loads((tmp_path / "r.json").read_text())
    prediction = np.array([s["prediction_um"] for s in result["samples"]])
    # the model's inputs as groupfit.features computes them, served by the rule's groups and its transfer
    served = ModelFile.coerce(model)
    inputs = served.inputs(data.frame, data.source)
    assert np.max(np.abs(prediction - served.predict(inputs, replay_groups(served, inputs), transfer=True))) <= 1e-9
    assert result["faults"] == {"held_samples": 0, "sensor_fault_samples": 0}
    if which == "modelling":  # the offline grouping itself, with the bumpless transfer at its switches
        expected = served.predict(inputs, served.serving_groups(len(inputs)), transfer=True)
        assert np.max(np.abs(prediction - expected)) <= 1e-9
        assert result["samples_off_offline_group"] == 0


def test_missing_source_column_is_named_with_the_input_it_feeds(tmp_path, capsys):
    model, _ = augmented_model("all kinds p=2")
    write_model(model, tmp_path / "model.json")
    data = tmp_path / "no_speed.csv"
    pd.read_csv(DIAG_AMBIENT[1]).drop(columns="speed_rpm").to_csv(data, index=False)
    assert replay(tmp_path / "model.json", "--data", data) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "column 'speed_rpm' not found" in err[0] and "speed_rpm~delay3" in err[0]


def test_source_faults_and_a_constant_source_in_a_recorded_run(tmp_path):
    model, _ = augmented_model("on/off p=1")
    write_model(model, tmp_path / "model.json")
    frame = pd.read_csv(DIAG_SOURCE[1])
    frame["src_zscrew_on"] = 0  # never on in this run: a valid reading, not a dead sensor
    frame.loc[10:11, "spindle_on"] = np.nan  # held
    frame.loc[100:106, "spindle_on"] = 7  # out of range: held, then a sensor fault
    frame.to_csv(tmp_path / "run.csv", index=False)
    assert replay(tmp_path / "model.json", "--data", tmp_path / "run.csv", "--json", tmp_path / "r.json") == 0
    result = json.loads((tmp_path / "r.json").read_text())
    faults = [s["fault"] for s in result["samples"]]
    assert faults[10:12] == [FAULT_HELD] * 2 and faults[100:107] == [FAULT_HELD] * 3 + [FAULT_SENSOR] * 4
    assert result["nonfinite_readings"] == 2 and result["faults"]["sensor_fault_samples"] == 4
    assert all(s["prediction_um"] == 0.0 for s in result["samples"][103:107])


def test_a_heat_law_effect_found_by_diagnose_replays_with_the_rms_diagnose_reports(tmp_path, capsys):
    """fit (p = 0), diagnose, replay: the bearing-heat law of a speed, low-passed from rest, end to end."""
    modelling, validation = heat_law_runs()  # speeds at several levels, at speed from a cold start
    data, check = tmp_path / "model.csv", tmp_path / "validate.csv"
    modelling.to_csv(data, index=False)
    validation.to_csv(check, index=False)
    fit = ["fit", "--data", data, "--temps", "T1,T2,T3,T4", "--p", "0", "--out", tmp_path / "m", "--quiet"]
    fit += ["--reference", "none"]  # the lumped machine's error is defined on absolute readings
    assert main([str(v) for v in fit]) == 0
    diagnose = ["diagnose", tmp_path / "m" / "model.json", "--data", data, "--validate", check]
    assert main([str(v) for v in [*diagnose, "--out", tmp_path / "d", "--json", tmp_path / "d.json"]]) == 0
    result = json.loads((tmp_path / "d.json").read_text())
    added = result["added"][0]
    assert (added["column"], added["transform"], added["tau_s"]) == ("speed_rpm", "lowpass", 1800.0)
    augmented = json.loads((tmp_path / "d" / "model_augmented.json").read_text())
    (entry,) = augmented["derived_inputs"]
    assert entry["name"] == "(speed_rpm/1000)^1.667~lp1800sr" and entry["start"] == "rest"
    for run, key in [(data, "data"), (check, "validate")]:
        out = tmp_path / f"replay_{key}.json"
        assert replay(tmp_path / "d" / "model_augmented.json", "--data", run, "--json", out) == 0
        replayed = json.loads(out.read_text())
        assert replayed["scored_samples"] == len(modelling)
        assert replayed["rms_um"] == pytest.approx(result["after"][key]["rms_um"], rel=1e-9, abs=1e-12)
        assert replayed["rms_um"] < 0.05  # the effect is removed: the error left is the 0.02 um noise
    capsys.readouterr()
