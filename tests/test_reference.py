"""Reference temperatures: stored in the model, applied alike offline, in replay and in every export."""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pytest
from support.json_runtime import run_table
from support.replay import assert_same_decisions, python_replay
from test_switching_models import DATASETS, noisy, shifted

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.export import render
from groupfit.export.harness import run_driver
from groupfit.metrics import error_metrics
from groupfit.model import ModelFile
from groupfit.models import GroupedRegressor
from groupfit.reference import parse_reference, referenced, with_reference
from groupfit.runtime import RuleTables, SwitchingRule, replay_groups

MODELLING = DATASETS / "paper_cycle.csv"
AMBIENT_25 = DATASETS / "repeat_ambient25.csv"
TEMPS = ["T1", "T2"]


@lru_cache(maxsize=None)
def _model(reference: str | None, p: int = 3) -> dict:
    run = with_reference(load_run(MODELLING, temps=TEMPS), reference)
    estimator = GroupedRegressor(p=p, search="exact").fit(run.temps, run.error)
    return estimator.to_model_file(run).to_dict()


def model_for(reference, p: int = 3) -> dict:
    return json.loads(json.dumps(_model(reference, p)))


def raw_readings(model: dict, path=MODELLING) -> np.ndarray:
    run = load_run(path, temps=TEMPS)
    return run.frame[list(RuleTables.from_model(model).raw_names)].to_numpy(dtype=float)


def live_rms(model: dict, path) -> float:
    """RMS of the model on a run, groups chosen by the run-time rule, as compare scores it."""
    model_file = ModelFile.from_dict(model)
    run = load_run(path, temps=TEMPS)
    inputs = model_file.inputs(run.frame, run.source)
    prediction = model_file.predict(inputs, replay_groups(model_file, inputs))
    return error_metrics(run.error - prediction)["rms_um"]


# the model file ---------------------------------------------------------------


def test_parse_reference():
    assert parse_reference(None) is None and parse_reference("none") is None and parse_reference("") is None
    assert parse_reference("start") == "start" and parse_reference(" T_amb ") == "T_amb"
    with pytest.raises(InputError):
        parse_reference(3)


def test_the_reference_is_a_model_file_key_and_round_trips(tmp_path):
    model = model_for("T_amb")
    assert model["reference"] == "T_amb" and list(model).index("reference") == list(model).index("temps") + 1
    path = tmp_path / "model.json"
    ModelFile.from_dict(model).save(path)
    assert ModelFile.load(path).reference == "T_amb"
    assert "reference" not in model_for(None)  # a model without one writes the file as before


def test_a_reference_that_is_an_input_is_refused():
    model = model_for("T_amb")
    model["reference"] = "T1"
    with pytest.raises(InputError, match="reference"):
        ModelFile.from_dict(model)
    with pytest.raises(InputError, match="also an input"):
        with_reference(load_run(MODELLING, temps=TEMPS), "T1")


def test_offline_inputs_are_rises_over_the_reference():
    run = load_run(MODELLING, temps=TEMPS)
    for reference in ("T_amb", "start"):
        model = ModelFile.from_dict(model_for(reference))
        inputs = model.inputs(run.frame)
        assert np.array_equal(inputs, referenced(run.temps, reference, run.frame))
    assert np.array_equal(
        ModelFile.from_dict(model_for("T_amb")).inputs(run.frame), run.temps - run.frame[["T_amb"]].to_numpy()
    )
    start = ModelFile.from_dict(model_for("start")).inputs(run.frame)
    assert np.all(start[0] == 0.0)


def test_a_run_without_the_reference_column_is_named(tmp_path):
    run = load_run(MODELLING, temps=TEMPS)
    with pytest.raises(InputError, match="T_amb"):
        ModelFile.from_dict(model_for("T_amb")).inputs(run.frame.drop(columns=["T_amb"]), "day2.csv")


# the must-show: another ambient -------------------------------------------------


@pytest.mark.parametrize("p", [0, 3])
def test_a_model_on_rises_over_the_ambient_survives_a_day_at_25_C(p):
    """Fitted at 20 C; the repeat at 25 C within 1.2x its RMS at 20 C. On absolute readings it fails."""
    referenced_model = model_for("T_amb", p)
    at_20 = referenced_model["training"]["rms_um"]
    at_25 = live_rms(referenced_model, AMBIENT_25)
    assert at_25 <= 1.2 * at_20, (at_20, at_25)

    absolute = model_for(None, p)
    assert absolute["training"]["rms_um"] <= 1.2 * at_20  # as good on its own day
    assert live_rms(absolute, AMBIENT_25) > 10 * at_20  # but the intercept holds the 20 C of that day


def test_the_start_reference_survives_another_ambient_too_when_started_cold():
    """Rises over each sensor's first reading: that one noisy reading offsets the whole run (a few 0.01 K
    times the coefficients), so the margin is wider than with an ambient sensor, but far from the failure."""
    model = model_for("start")
    at_25 = live_rms(model, AMBIENT_25)
    assert at_25 <= 1.5 * model["training"]["rms_um"]
    assert at_25 < 0.05 * live_rms(model_for(None), AMBIENT_25)


# the run-time rule and the exports -----------------------------------------------


def reference_faults(raw: np.ndarray, tables: RuleTables) -> np.ndarray:
    """The reference sensor held, in fault, out of range; the start reading invalid at first."""
    raw = np.array(raw, dtype=float)
    hold = tables.hold_samples
    r = tables.reference_reading if tables.reference_reading >= 0 else 0
    raw[0:2, 0] = np.nan  # sensor 1 invalid before its first good reading (start: its first reading is late)
    raw[30 : 30 + hold, r] = np.nan  # held: the last good reference stands in
    raw[60 : 60 + hold + 4, r] = np.inf  # fault: safe output, then recovery
    raw[120, r] = tables.valid_max[r] + 1.0  # out of range: held
    raw[121, r] = tables.valid_min[r] - 1.0
    raw[200 : 200 + 2 * hold, r] = -np.inf
    return raw


def streams(model: dict) -> dict[str, np.ndarray]:
    tables = RuleTables.from_model(model)
    raw = raw_readings(model)
    n = int(model["n"])
    return {
        "modelling": raw,
        "25 C": raw_readings(model, AMBIENT_25),
        "noise 0.05 C": noisy(raw, 0.05, seed=1),
        f"late by {n}": shifted(raw, n),
        "reference faults": reference_faults(raw, tables),
    }


def test_the_reference_column_is_one_more_reading():
    tables = RuleTables.from_model(model_for("T_amb"))
    assert tables.raw_names == ("T1", "T2", "T_amb") and tables.reference_reading == 2
    assert tables.valid_min[2] <= 20.0 <= 25.0 <= tables.valid_max[2]
    start = RuleTables.from_model(model_for("start"))
    assert start.raw_names == ("T1", "T2") and start.reference_reading == -1 and start.reference_start


@pytest.mark.parametrize("reference", ["T_amb", "start"])
def test_replay_of_the_modelling_run_is_the_offline_model(reference):
    model = model_for(reference)
    result = SwitchingRule(model).replay(raw_readings(model))
    model_file = ModelFile.from_dict(model)
    run = load_run(MODELLING, temps=TEMPS)
    inputs = model_file.inputs(run.frame)
    expected = model_file.predict(inputs, result.group - 1, transfer=True)  # with the bumpless transfer
    np.testing.assert_allclose(result.prediction_um, expected, atol=1e-12)
    assert np.array_equal(result.group - 1, replay_groups(model_file, inputs))


def test_a_faulty_reference_is_a_faulty_reading():
    model = model_for("T_amb")
    tables = RuleTables.from_model(model)
    hold = tables.hold_samples
    result = SwitchingRule(model).replay(reference_faults(raw_readings(model), tables))
    assert np.all(result.fault[30 : 30 + hold] == 1)  # held, output valid
    in_fault = slice(60 + hold, 60 + hold + 4)
    assert np.all(result.fault[in_fault] & 2) and np.all(result.prediction_um[in_fault] == 0)
    assert result.fault[120] == 1 and result.fault[121] == 1
    assert result.fault[70] == 0  # recovered


def test_start_reference_takes_each_sensor_from_its_first_good_reading():
    model = model_for("start")
    raw = raw_readings(model)
    late = raw.copy()
    late[0:2, 0] = np.nan
    rule = SwitchingRule(model)
    rule.replay(late)
    assert rule.first[0] == late[2, 0] and rule.first[1] == raw[0, 1]


@pytest.mark.parametrize("reference", ["T_amb", "start"])
@pytest.mark.parametrize("single", [False, True])
def test_c_build_makes_the_decisions_of_replay_bit_for_bit(drivers, reference, single):
    model = model_for(reference)
    chosen = streams(model)
    outputs = run_driver(drivers(reference, model, "single" if single else "double"), list(chosen.values()))
    for temps, c_out in zip(chosen.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps, "single" if single else "double"))


def test_c_header_names_the_reference():
    header = render(model_for("T_amb"), "c")["groupfit_model.h"]
    assert "#define GF_REFERENCE 2" in header and "temps[2] = T_amb" in header and "reference" in header
    header = render(model_for("start"), "c")["groupfit_model.h"]
    assert "GF_REFERENCE_START" in header and "first[GF_N_TEMPS]" in header


@pytest.mark.parametrize("reference", [pytest.param("T_amb", marks=pytest.mark.slow), "start"])
@pytest.mark.toolchain
def test_lreal_block_matches_replay(reference):
    from support.structured_text import assert_lreal_block_replays

    model = model_for(reference)
    assert_lreal_block_replays(model, streams(model).values())


@pytest.mark.parametrize("reference", ["T_amb", pytest.param("start", marks=pytest.mark.slow)])
def test_real_block_matches_the_single_precision_c_build_bit_for_bit(drivers, reference):
    from support.structured_text import as_single, assert_same_decisions, run_block

    model = model_for(reference)
    (text,) = render(model, "st", real="REAL").values()
    chosen = as_single(list(streams(model).values()))
    st_out = run_block(text, chosen, model["sampling_period_s"], "REAL")
    c_out = run_driver(drivers(reference, model, "single"), chosen)
    assert_same_decisions(st_out, c_out)


@pytest.mark.parametrize("reference", ["T_amb", "start"])
def test_json_table_is_enough_to_rebuild_the_rule_with_a_reference(reference):
    model = model_for(reference)
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    assert table["format"] == "groupfit-runtime/7" and table["reference"]["kind"] in ("column", "start")
    assert any(step.startswith("reference") for step in table["steps"])
    rule = SwitchingRule(model)
    for temps in streams(model).values():
        rule.reset()
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected


def test_controller_sheet_states_the_reference():
    sheet = render(model_for("T_amb"), "sheet")
    text = sheet["groupfit_sheet.txt"]
    assert "T_amb" in text and "Reference temperature" in text and "reference of every measured input" in text
    assert json.loads(sheet["groupfit_sheet.json"])["reference"]["reference"] == "T_amb"
    assert "first good reading" in render(model_for("start"), "sheet")["groupfit_sheet.txt"]


# the verbs ------------------------------------------------------------------------


def test_fit_stores_the_reference_and_replay_reads_the_reference_column(tmp_path, capsys):
    out = tmp_path / "model"
    args = ["fit", "--data", str(MODELLING), "--temps", "T1,T2", "--p", "2", "--search", "exact", "--quiet"]
    assert main([*args, "--reference", "T_amb", "--out", str(out)]) == 0
    assert ModelFile.load(out / "model.json").reference == "T_amb"
    report = tmp_path / "replay.json"
    assert main(["replay", str(out / "model.json"), "--data", str(AMBIENT_25), "--json", str(report)]) == 0
    replayed = json.loads(report.read_text())
    assert replayed["rms_um"] <= 1.2 * ModelFile.load(out / "model.json").training["rms_um"]
    capsys.readouterr()
    broken = tmp_path / "no_ambient.csv"
    load_run(AMBIENT_25, temps=TEMPS).frame.drop(columns=["T_amb"]).to_csv(broken, index=False)
    assert main(["replay", str(out / "model.json"), "--data", str(broken)]) == 2
    assert "T_amb" in capsys.readouterr().err


def test_fit_default_reference_is_the_ambient_column_and_none_turns_it_off(tmp_path):
    # the reference is the model file's whatever the break search: one least-squares fit (p = 0) shows it
    args = ["fit", "--data", str(MODELLING), "--temps", "T1,T2", "--p", "0", "--quiet"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    assert ModelFile.load(tmp_path / "a" / "model.json").reference == "T_amb"
    assert main([*args, "--reference", "none", "--out", str(tmp_path / "b")]) == 0
    assert ModelFile.load(tmp_path / "b" / "model.json").reference is None
    assert main([*args, "--reference", "start", "--out", str(tmp_path / "c")]) == 0
    assert ModelFile.load(tmp_path / "c" / "model.json").reference == "start"


def test_fit_refuses_a_missing_reference_column(tmp_path, capsys):
    args = ["fit", "--data", str(MODELLING), "--temps", "T1,T2", "--p", "1", "--quiet", "--out", str(tmp_path)]
    assert main([*args, "--reference", "T_bed"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "T_bed" in err[0]


def test_diagnose_runs_on_a_referenced_model(tmp_path):
    model_dir = tmp_path / "model"
    data = DATASETS / "diag_none_model.csv"
    args = ["fit", "--data", str(data), "--temps", "T1,T2,T3,T4", "--p", "0", "--reference", "T_amb"]
    assert main([*args, "--out", str(model_dir), "--quiet"]) == 0
    report = tmp_path / "diagnose.json"
    diagnose = ["diagnose", str(model_dir / "model.json"), "--data", str(data), "--json", str(report)]
    assert main([*diagnose, "--out", str(tmp_path / "d")]) == 0
    result = json.loads(report.read_text())
    assert result["before"]["data"]["rms_um"] > 0
    augmented = ModelFile.load(result["model"])
    assert augmented.reference == "T_amb"


def test_a_global_model_on_several_runs_takes_each_from_its_own_start(tmp_path):
    out = tmp_path / "model"
    data = [str(MODELLING), str(AMBIENT_25)]
    args = ["fit", "--data", *data, "--temps", "T1,T2", "--p", "0", "--reference", "start", "--quiet"]
    assert main([*args, "--out", str(out)]) == 0
    model = ModelFile.load(out / "model.json")
    assert model.reference == "start"
    runs = [load_run(path, temps=TEMPS) for path in data]
    X = np.vstack([referenced(run.temps, "start") for run in runs])
    A = np.column_stack([np.ones(len(X)), X])
    expected = np.linalg.lstsq(A, np.concatenate([run.error for run in runs]), rcond=None)[0]
    assert model.training["rms_um"] < 0.5
    np.testing.assert_allclose(np.asarray(model.coefficients[0]), expected, rtol=1e-3, atol=1e-3)
