"""replay compares a next run's error with the figure fit expected of it (the model file's training)."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main
from groupfit.commands.replay_faults import fault_readings
from groupfit.model import ModelFile
from groupfit.runtime import FAULT_HELD, SwitchingRule


def heated_run(seed: int, ambient: float, hours: float = 6.0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, hours * 3600.0, 60.0)
    heat = ((t // 5400) % 2 == 0).astype(float)
    rise = np.zeros_like(t)
    for i in range(1, len(t)):
        rise[i] = rise[i - 1] + 60.0 / 1500.0 * (12.0 * heat[i] - rise[i - 1])
    frame = pd.DataFrame({"time_s": t, "T1": ambient + rise, "T2": ambient + 0.4 * rise + rng.normal(0, 0.05, len(t))})
    frame["T1"] += rng.normal(0, 0.05, len(t))
    frame["error_um"] = 2.0 * rise + 0.8 * np.sin(t / 3000.0) + rng.normal(0, 0.2, len(t))
    return frame


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    folder = tmp_path_factory.mktemp("expectation")
    model_run, next_run = folder / "a.csv", folder / "b.csv"
    heated_run(1, 21.0).to_csv(model_run, index=False)
    heated_run(2, 21.5).to_csv(next_run, index=False)
    assert main(["fit", "--data", str(model_run), "--p", "0", "--out", str(folder / "fit"), "--quiet"]) == 0
    return folder / "fit" / "model.json", model_run, next_run


def replay_json(tmp_path, *args) -> dict:
    out = tmp_path / "r.json"
    assert main(["replay", *map(str, args), "--json", str(out)]) == 0
    return json.loads(out.read_text())


def rms(result: dict) -> float:
    residual = np.array([s["residual_um"] for s in result["samples"]], dtype=float)
    return float(np.sqrt(np.nanmean(residual**2)))


def test_a_next_run_is_placed_against_the_expected_figure_and_its_range(tmp_path, fitted, capsys):
    model_path, _, next_run = fitted
    training = ModelFile.load(model_path).training
    result = replay_json(tmp_path, model_path, "--data", next_run)
    check = result["expected_next_run"]
    low, high = training["expected_next_run_range_um"]
    assert check["rms_um"] == training["expected_next_run_rms_um"]
    assert check["range_um"] == [low, high]
    assert check["actual_rms_um"] == pytest.approx(rms(result), rel=1e-12)
    assert check["actual_over_expected"] == pytest.approx(rms(result) / training["expected_next_run_rms_um"])
    assert check["place"] == ("below" if rms(result) < low else "above" if rms(result) > high else "inside")
    assert f"this run without checks: {rms(result):.3g} µm" in capsys.readouterr().out


def test_with_checks_the_run_is_judged_without_them(tmp_path, fitted):
    model_path, _, next_run = fitted
    plain = replay_json(tmp_path, model_path, "--data", next_run)
    checked = replay_json(tmp_path, model_path, "--data", next_run, "--probe-every", 1800)
    assert checked["rms_um"] != pytest.approx(plain["rms_um"])
    assert checked["expected_next_run"]["actual_rms_um"] == pytest.approx(plain["rms_um"], rel=1e-12)


def test_the_modelling_file_is_not_taken_for_a_next_run(tmp_path, fitted, capsys):
    model_path, model_run, _ = fitted
    result = replay_json(tmp_path, model_path, "--data", model_run)
    assert result["expected_next_run"]["place"] == "modelling run"
    assert "one the model was fitted on, not a next run" in capsys.readouterr().out
    copy = tmp_path / "copy_of_the_modelling_run.csv"
    pd.read_csv(model_run).assign(error_um=lambda f: f.error_um + 0.5).to_csv(copy, index=False)
    assert replay_json(tmp_path, model_path, "--data", copy)["expected_next_run"]["place"] != "modelling run"


def test_a_model_file_without_an_expectation_gets_no_comparison(tmp_path, capsys):
    model, _ = synthetic_model()
    path = tmp_path / "model.json"
    ModelFile.from_dict(model).save(path)
    assert "expected_next_run_rms_um" not in (ModelFile.load(path).training or {})
    result = replay_json(tmp_path, path, "--data", SYNTHETIC)
    assert "expected_next_run" not in result
    assert "expected about" not in capsys.readouterr().out


def test_a_next_run_logged_in_another_unit_is_not_placed_and_its_readings_are_named(tmp_path, fitted, capsys):
    """The next run logged in °F, for most of it, under the modelling run's names: the rule holds the readings
    beyond their valid range and faults, so the few samples scored are not the run; replay names the readings,
    their range and the values seen, and does not place the run against the expected figure."""
    model_path, _, next_run = fitted
    frame = pd.read_csv(next_run)
    later = frame.index >= 0.3 * len(frame)  # the logger switched to °F after the first 30 % of the run
    for column in ("T1", "T2"):
        frame.loc[later, column] = frame.loc[later, column] * 9.0 / 5.0 + 32.0
    frame.to_csv(tmp_path / "fahrenheit.csv", index=False)
    result = replay_json(tmp_path, model_path, "--data", tmp_path / "fahrenheit.csv")
    assert result["scored_samples"] < 0.5 * result["measured_samples"]
    assert 0 < result["scored_samples"] and result["expected_next_run"]["place"] == "mostly unscored"
    tables = SwitchingRule(ModelFile.load(model_path)).tables
    found = {f["reading"]: f for f in result["readings_out_of_range"]}
    for r, name in enumerate(tables.raw_names):
        values = frame[name].to_numpy()
        outside = (values < tables.valid_min[r]) | (values > tables.valid_max[r])
        assert found[name]["samples"] == int(outside.sum())
        assert found[name]["seen"] == [values[outside].min(), values[outside].max()]
    assert any("another unit" in note for note in result["notes"])
    clean = replay_json(tmp_path, model_path, "--data", next_run)
    assert "readings_out_of_range" not in clean and clean["expected_next_run"]["place"] != "mostly unscored"


def test_a_reading_both_missing_and_out_of_range_is_named_with_each_count():
    tables = SimpleNamespace(raw_names=["speed_rpm"], valid_min=np.array([0.0]), valid_max=np.array([8000.0]))
    speed = np.full((10, 1), 1000.0)
    speed[2:5, 0] = np.nan
    speed[7, 0] = -5.0
    found, notes = fault_readings(tables, speed, np.full(10, FAULT_HELD))
    assert found["readings_out_of_range"][0]["samples"] == 4
    assert "speed_rpm -5..-5 on 1 sample(s) and not finite (NaN or ±inf) on 3 sample(s) (valid 0..8000)" in notes[0]
    speed[7, 0] = 1000.0
    _, notes = fault_readings(tables, speed, np.full(10, FAULT_HELD))
    assert "speed_rpm not finite (NaN or ±inf) on 3 sample(s) (valid" in notes[0]
