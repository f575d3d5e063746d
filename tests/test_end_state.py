"""The rule's state at the end of a modelling file, kept in the model file, stands in for the file when it is gone."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.diagnose_scenarios import SPINDLE_SENSORS, spindle_run

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.runtime import RuleTables, SwitchingRule
from groupfit.runtime.state import capture, restore

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
CUT = 330


def cli(*args) -> int:
    return main([str(a) for a in args])


def replayed(model: Path, data: Path, *args) -> tuple[dict, str]:
    out = model.parent / "replay.json"
    assert cli("replay", model, "--data", data, *args, "--json", out) == 0
    return json.loads(out.read_text())


def moved_away(folder: Path, model_name: str, modelling: str) -> Path:
    """The model file copied into a folder of its own, its modelling file not there: the file is gone."""
    away = folder / "away"
    away.mkdir(exist_ok=True)
    model = json.loads((folder / model_name).read_text())
    for entry in model["training"]["recordings"]:
        entry["path"] = str(away / modelling)
        entry["path_from_model"] = modelling
    (away / model_name).write_text(json.dumps(model))
    return away / model_name


@pytest.fixture(scope="module")
def grouped(tmp_path_factory):
    """The paper cycle cut at row CUT, a grouped model with its recalibration fitted on the first part."""
    folder = tmp_path_factory.mktemp("end_state")
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    whole.iloc[:CUT].to_csv(folder / "first.csv", index=False)
    whole.iloc[CUT:].to_csv(folder / "rest.csv", index=False)
    assert cli("fit", "--data", folder / "first.csv", "--p", "2", "--temps", "T1,T2,T3,T4", "--out", folder) == 0
    return folder


@pytest.mark.parametrize("precision", ["double", "single"])
def test_a_rest_replayed_from_the_kept_state_equals_the_rest_replayed_after_the_modelling_file(grouped, precision):
    args = ("--probe-every", "1800", "--precision", precision)
    after_file = replayed(grouped / "model.json", grouped / "rest.csv", *args)
    assert after_file["history_samples"] == CUT and after_file["samples"][0]["group"] > 1
    away = moved_away(grouped, "model.json", "first.csv")
    from_state = replayed(away, grouped / "rest.csv", *args)
    assert from_state["continues"] == [str(away.parent / "first.csv")]
    where = {"continues", "model"}  # the model file and the file it continues lie elsewhere
    assert {k: v for k, v in from_state.items() if k not in where} == {
        k: v for k, v in after_file.items() if k not in where
    }
    fresh = replayed(away, grouped / "rest.csv", *args, "--fresh")
    assert fresh["history_samples"] == 0 and fresh["samples"][0]["group"] == 1


def test_the_state_of_a_diagnosed_model_carries_its_derived_inputs_across(tmp_path, capsys):
    frame = spindle_run(8, hours=16.0)
    at = int(np.flatnonzero(frame["speed_rpm"].to_numpy() >= 4000.0)[-1]) - 60  # cut while the spindle runs fast
    frame.iloc[:at].to_csv(tmp_path / "first.csv", index=False)
    rest = frame.iloc[at:].reset_index(drop=True)
    rest["time_s"] -= rest["time_s"].iloc[0]  # the rest on a clock of its own, told by its first row
    rest.to_csv(tmp_path / "rest.csv", index=False)
    fit = ("fit", "--data", tmp_path / "first.csv", "--temps", ",".join(SPINDLE_SENSORS[:2]), "--p", "0")
    assert cli(*fit, "--reference", "none", "--out", tmp_path) == 0
    assert cli("diagnose", tmp_path / "model.json", "--data", tmp_path / "first.csv", "--out", tmp_path) == 0
    augmented = ModelFile.load(tmp_path / "model_augmented.json")
    assert any(d.column == "speed_rpm" for d in augmented.derived_inputs)
    after_file = replayed(tmp_path / "model_augmented.json", tmp_path / "rest.csv", "--probe-every", "3600")
    away = moved_away(tmp_path, "model_augmented.json", "first.csv")
    capsys.readouterr()
    from_state = replayed(away, tmp_path / "rest.csv", "--probe-every", "3600")
    assert "no longer there: replayed from the rule's state at that file's end" in capsys.readouterr().out
    assert from_state["samples"] == after_file["samples"] and from_state["rms_um"] == after_file["rms_um"]
    assert replayed(away, tmp_path / "rest.csv", "--fresh")["rms_um"] != after_file["rms_um"]


def test_capture_and_restore_go_on_as_the_rule_that_ran_through(grouped):
    model = ModelFile.load(grouped / "model.json")
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    tables = RuleTables.from_model(model)
    readings = whole[list(tables.raw_names)].to_numpy(dtype=float)
    readings[CUT + 5, 1] = np.nan  # a sensor fault just after the cut: its hold counter crosses it
    checks = np.full(len(readings), np.nan)
    checks[CUT - 40 :: 25] = whole["error_um"].to_numpy()[CUT - 40 :: 25] + 0.3
    for precision in ("double", "single"):
        rule = SwitchingRule(model, precision=precision, period_s=100.0)
        through = rule.replay(readings, checks).tail(CUT)
        rule.replay(readings[:CUT], checks[:CUT])
        state = json.loads(json.dumps(capture(rule)))  # as the model file keeps it
        going_on = rule.replay(readings[CUT:], checks[CUT:], state)
        for name in ("group", "prediction_um", "compensation_um", "fault", "switched", "probe", "target_um"):
            np.testing.assert_array_equal(getattr(going_on, name), getattr(through, name))


def test_a_kept_state_that_does_not_fit_the_model_is_refused_in_one_line(grouped, capsys):
    away = moved_away(grouped, "model.json", "first.csv")
    model = json.loads(away.read_text())
    last = model["training"]["recordings"][0]["end_state"]["double"]["rule"]["last"]
    assert len(last) == 5  # four sensors and the ambient reference
    last.pop()
    (away.parent / "cut.json").write_text(json.dumps(model))
    capsys.readouterr()
    assert cli("replay", away.parent / "cut.json", "--data", grouped / "rest.csv") == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "training.recordings[0].end_state.double.rule.last must be a list of 5" in line
    model["training"]["recordings"][0]["end_state"]["samples"] = 0
    (away.parent / "bad.json").write_text(json.dumps(model))
    with pytest.raises(InputError, match=r"training.recordings\[0\].end_state must hold samples"):
        ModelFile.load(away.parent / "bad.json")
    rule = SwitchingRule(ModelFile.load(away), period_s=100.0)
    with pytest.raises(InputError, match="does not hold the state of this model's rule"):
        restore(rule, {"rule": {}, "recalibration": {}})
