"""A validation run's fault codes and missed heat readings are scored as ``replay`` scores them.

A sensor that logs a fault code (-999 °C, 850 °C) or a reading beyond the
valid range of the run-time rule is, for the rule, what an empty cell is: the
reading is held for the rule's hold, then the rule is in sensor fault and those
samples are not scored. ``compare`` and ``diagnose`` refused such a validation
run when the reading was beyond the plausible range, and scored the offline
model on it (predicting from the reading as logged) when it was within that
range but beyond the rule's. Their figures on such a run are now ``replay``'s
of the same model file.

The AR(1) model's heat reading missed on some rows of a validation run (an
empty cell, ±inf) made ``compare`` refuse the run; the AR(1) routine, as
``replay`` of an AR(1) model file runs it, holds its state there, and
``compare``'s AR(1) row is now scored so. A reading below 0 (a speed logged
with its sense of rotation) is still refused (tests/test_bad_inputs.py).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.validation import assert_judged_as_replayed, run_json

from groupfit.cli import main
from groupfit.data import TEMP_RANGE_C

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
MODELLING = DATASETS / "paper_cycle.csv"
CLEAN = DATASETS / "validation_timing.csv"
FAULTY_ROWS = slice(200, 209)  # ten rows, longer than the rule's hold
SPIKE_ROWS = slice(300, 301)  # two rows, within the rule's hold: held, never in fault


def hold_of(model: Path) -> int:
    return json.loads(model.read_text())["switching"]["hold_samples"]


def written(tmp: Path, name: str, change) -> Path:
    frame = pd.read_csv(CLEAN)
    change(frame)
    frame.to_csv(tmp / f"{name}.csv", index=False)
    return tmp / f"{name}.csv"


def set_rows(column: str, rows: slice, value):
    def change(frame: pd.DataFrame) -> None:
        frame[column] = frame[column].astype(float)
        frame.loc[rows, column] = value

    return change


def both(*changes):
    def change(frame: pd.DataFrame) -> None:
        for one in changes:
            one(frame)

    return change


UNMEASURED = set_rows("error_um", slice(FAULTY_ROWS.start, FAULTY_ROWS.start + 4), np.nan)  # 5 of the 10 rows


def row_of(result: dict, model: str, run: str) -> dict:
    return next(r for r in result["rows"] if r["model"] == model and r["run"] == run)


def rule_range(model: Path, sensor: str) -> tuple[float, float]:
    data = json.loads(model.read_text())
    j = data["temps"].index(sensor)
    return data["switching"]["temp_min_c"][j], data["switching"]["temp_max_c"][j]


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, Path]:
    """The model fit writes (its choice, p = 0 with a ridge penalty), the least-squares MLR as compare fits it,
    and the AR(1) model as compare fits it (its free run from the first measured error)."""
    tmp = tmp_path_factory.mktemp("models")
    assert main([str(a) for a in ["fit", "--data", MODELLING, "--out", tmp / "chosen", "--quiet"]]) == 0
    plain = ["fit", "--data", MODELLING, "--p", "0", "--recalibrate", "none", "--out", tmp / "mlr", "--quiet"]
    assert main([str(a) for a in plain]) == 0
    ar1 = ["fit", "--data", MODELLING, "--model", "ar1", "--heat", "speed_rpm", "--start", "measured"]
    assert main([str(a) for a in [*ar1, "--out", tmp / "ar1", "--quiet"]]) == 0
    return {name: tmp / name / "model.json" for name in ("chosen", "mlr", "ar1")}


@pytest.fixture(scope="module")
def faulty_runs(tmp_path_factory, models) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("runs")
    low, high = rule_range(models["mlr"], "T3")
    inside = high + 0.5 * (TEMP_RANGE_C[1] - high)  # plausible, beyond the rule's range
    assert TEMP_RANGE_C[0] < low and high < inside < TEMP_RANGE_C[1]
    return {
        "code": written(tmp, "code", set_rows("T3", FAULTY_ROWS, -999.0)),  # beyond the plausible range
        "hot": written(tmp, "hot", set_rows("T3", FAULTY_ROWS, inside)),
        "spike": written(tmp, "spike", set_rows("T3", SPIKE_ROWS, 850.0)),
        "reference": written(tmp, "reference", set_rows("T_amb", FAULTY_ROWS, -999.0)),  # the inputs' reference
        "unheated": written(tmp, "unheated", set_rows("speed_rpm", FAULTY_ROWS, np.nan)),
        "infinite": written(tmp, "infinite", set_rows("speed_rpm", SPIKE_ROWS, np.inf)),
        "unmeasured": written(tmp, "unmeasured", both(set_rows("speed_rpm", FAULTY_ROWS, np.nan), UNMEASURED)),
    }


@pytest.fixture(scope="module")
def compared(tmp_path_factory, faulty_runs) -> dict:
    tmp = tmp_path_factory.mktemp("compared")
    report = tmp / "compare.json"
    args = ["compare", "--data", MODELLING, "--validate", CLEAN, *faulty_runs.values(), "--pmax", "0"]
    assert main([str(a) for a in [*args, "--json", report, "--out", tmp / "cmp", "--quiet"]]) == 0
    return json.loads(report.read_text())


@pytest.mark.parametrize("run, sensor", [("code", "T3"), ("hot", "T3"), ("spike", "T3"), ("reference", "T_amb")])
def test_compare_scores_a_fault_code_of_a_validation_run_as_replay_does(
    compared, models, faulty_runs, capsys, run, sensor
):
    """-999 °C in an input was refused as implausible; a reading beyond the rule's range, or -999 °C in the
    reference the inputs are taken against, was scored by the MLR as logged. Each is now held, then a sensor
    fault, and each model file's figure is replay's of it on the run."""
    rows = FAULTY_ROWS if run != "spike" else SPIKE_ROWS
    n = rows.stop - rows.start + 1
    hold = json.loads(models["mlr"].read_text())["switching"]["hold_samples"]
    for model, path in (("mlr", models["mlr"]), ("fit", models["chosen"])):
        replayed = run_json(capsys, "replay", path, "--data", faulty_runs[run])
        assert replayed["faults"]["sensor_fault_samples"] == max(0, n - hold)
        row = row_of(compared, model, run)
        assert row["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)
        assert row["max_um"] == pytest.approx(replayed["max_um"], rel=0, abs=1e-6)
    note = next(note for note in compared["notes"] if note.startswith(f"{run}: {sensor} "))
    assert f"on {n} sample(s) (valid " in note
    assert f"{max(0, n - hold)} sample(s) in sensor fault are not scored" in note


@pytest.mark.parametrize("run, held", [("unheated", FAULTY_ROWS), ("infinite", SPIKE_ROWS)])
def test_compare_holds_the_ar1_state_on_a_missed_heat_reading_as_its_routine_does(
    compared, models, faulty_runs, capsys, run, held
):
    """speed_rpm empty on ten rows (or inf on two): compare refused the run ("has no reading"); its AR(1) row is
    the AR(1) routine's (fit --model ar1, replayed) on the run, which holds its state on such a reading, and
    the other models score as on the clean run (they do not read the heat column)."""
    n = held.stop - held.start + 1
    replayed = run_json(capsys, "replay", models["ar1"], "--data", faulty_runs[run])
    assert sum(1 for s in replayed["samples"] if s["fault"]) == n
    row = row_of(compared, "ar1", run)
    assert row["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)
    assert row["max_um"] == pytest.approx(replayed["scores"]["max_um"], rel=0, abs=1e-6)
    clean = run_json(capsys, "replay", models["ar1"], "--data", CLEAN)
    assert abs(row["rms_um"] - clean["rms_um"]) > 1e-5  # the state held is not the clean run's free run
    for model in ("mlr", "fit"):
        assert row_of(compared, model, run)["rms_um"] == row_of(compared, model, "validation_timing")["rms_um"]
    note = next(note for note in compared["notes"] if note.startswith(f"{run}: AR(1) heat column 'speed_rpm'"))
    assert f"{n} of those sample(s) are scored on the held state" in note and "the others" not in note
    assert f"'speed_rpm': {n} sample(s) without a reading" in note


def test_the_held_heat_note_counts_only_the_samples_it_scores(compared, models, faulty_runs, capsys):
    """Ten rows without a heat reading, five of them without a measured error: five are scored on the held
    state (the note said ten), and the AR(1) row is still replay's."""
    note = next(n for n in compared["notes"] if n.startswith("unmeasured: AR(1) heat column 'speed_rpm'"))
    assert "'speed_rpm': 10 sample(s) without a reading" in note
    assert "5 of those sample(s) are scored on the held state (the others have no measured error)" in note
    replayed = run_json(capsys, "replay", models["ar1"], "--data", faulty_runs["unmeasured"])
    assert row_of(compared, "ar1", "unmeasured")["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)


def test_a_heat_column_empty_throughout_a_validation_run_is_refused(tmp_path, capsys):
    dead = written(tmp_path, "dead", set_rows("speed_rpm", slice(None), np.nan))
    capsys.readouterr()
    args = ["compare", "--data", MODELLING, "--validate", dead, "--pmax", "0", "--quiet", "--out", tmp_path / "c"]
    assert main([str(a) for a in args]) == 2
    assert "heat column 'speed_rpm' has no reading on any row" in capsys.readouterr().err


def test_a_modelling_run_with_a_missed_heat_reading_or_a_fault_code_is_still_refused(tmp_path, capsys):
    for column, value, message in (
        ("speed_rpm", np.nan, "column 'speed_rpm' has no reading"),
        ("T3", -999.0, "-999 °C is outside the plausible range"),
    ):
        frame = pd.read_csv(MODELLING)
        frame.loc[FAULTY_ROWS, column] = value
        frame.to_csv(tmp_path / "modelling.csv", index=False)
        capsys.readouterr()
        args = ["compare", "--data", tmp_path / "modelling.csv", "--validate", CLEAN, "--out", tmp_path / "c"]
        assert main([str(a) for a in [*args, "--pmax", "0", "--quiet"]]) == 2
        assert message in capsys.readouterr().err


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory) -> dict:
    tmp = tmp_path_factory.mktemp("diagnosed")
    fit = ["fit", "--data", DATASETS / "diag_speed_model.csv", "--temps", "T1,T2", "--p", "0", "--ridge", "0"]
    assert main([str(a) for a in [*fit, "--recalibrate", "none", "--out", tmp / "m", "--quiet"]]) == 0
    model = tmp / "m" / "model.json"
    frame = pd.read_csv(DATASETS / "diag_speed_validate.csv")
    frame.loc[299:318, "T1"] = -999.0  # twenty rows of a fault code
    frame.to_csv(tmp / "code.csv", index=False)
    report = tmp / "diagnose.json"
    args = ["diagnose", model, "--data", DATASETS / "diag_speed_model.csv", "--validate", tmp / "code.csv"]
    assert main([str(a) for a in [*args, "--recalibrate", "none", "--json", report, "--out", tmp / "d"]]) == 0
    return {"model": model, "run": tmp / "code.csv", "report": json.loads(report.read_text()), "out": tmp / "d"}


def test_diagnose_judges_on_a_validation_run_with_a_fault_code_as_replay_scores_it(diagnosed, capsys):
    """diagnose refused the run ("outside the plausible range"); its before and after on it are replay's of the
    model and of the augmented model on the same run."""
    report = diagnosed["report"]
    augmented = diagnosed["out"] / "model_augmented.json"
    assert report["added"] and report["model"] == str(augmented)
    models = {"before": diagnosed["model"], "after": augmented}
    assert_judged_as_replayed(capsys, report, models, diagnosed["run"], lambda path: 20 - hold_of(path))
    hold = hold_of(augmented)
    note = next(n for n in report["notes"] if n.startswith("code: "))
    assert "T1 -999..-999 on 20 sample(s)" in note
    assert f"{20 - hold} sample(s) in sensor fault are not scored" in note
