"""A validation run is scored as ``replay`` scores a next run, and compare scores the model ``fit`` writes.

A sensor that drops out on a validation run (empty cells) is a sensor fault of
the run-time rule: the reading is held for the rule's hold, then the rule is in
fault and commands nothing, and those samples are not scored. ``compare`` and
``diagnose`` read their ``--validate`` runs so, and their figures on such a
run are ``replay``'s of the same model file; a modelling run with such cells is
still refused (a model is fitted on finite values). ``compare`` also scores the
model ``fit`` writes when that is another than the least-squares MLR (the
ridge penalty and fast-response stage ``fit`` gives its choice p = 0), and its
figure on a validation run is ``fit`` then ``replay`` on that run.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.validation import assert_judged_as_replayed, run_json

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
MODELLING = DATASETS / "paper_cycle.csv"
CLEAN = DATASETS / "validation_timing.csv"
HOLD_SAMPLES = 3  # 300 s at 100 s


def with_dropouts(source: Path, target: Path, column: str, first: int, count: int) -> Path:
    """``source`` with ``column`` empty on ``count`` rows from the 1-based data row ``first``, and the ambient
    sensor empty on two rows later on (held, never a fault)."""
    frame = pd.read_csv(source)
    frame.loc[first - 1 : first + count - 2, column] = np.nan
    frame.loc[first + count + 99 : first + count + 100, "T_amb"] = np.nan
    frame.to_csv(target, index=False)
    return target


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("faults")
    faulty = with_dropouts(DATASETS / "repeat_ambient25.csv", tmp / "dropout.csv", "T3", 200, 16)
    report = tmp / "compare.json"
    compare = ["compare", "--data", MODELLING, "--validate", CLEAN, faulty, "--pmax", "1", "--json", report]
    assert main([str(a) for a in [*compare, "--out", tmp / "cmp", "--quiet"]]) == 0
    assert main([str(a) for a in ["fit", "--data", MODELLING, "--out", tmp / "chosen", "--quiet"]]) == 0
    plain = ["fit", "--data", MODELLING, "--p", "0", "--recalibrate", "none", "--out", tmp / "mlr", "--quiet"]
    assert main([str(a) for a in plain]) == 0
    return {
        "compare": json.loads(report.read_text()),
        "chosen": tmp / "chosen" / "model.json",
        "mlr": tmp / "mlr" / "model.json",
        "faulty": faulty,
    }


def row_of(result: dict, model: str, run: str) -> dict:
    return next(r for r in result["rows"] if r["model"] == model and r["run"] == run)


def test_compare_scores_the_model_fit_writes_as_fit_then_replay_score_it(compared, capsys):
    """The run fit chooses p = 0 on: it writes the global model with a ridge penalty and a fast-response stage,
    not the least-squares MLR; compare's row of that model on a next run is fit's model replayed on it."""
    result = compared["compare"]
    chosen = json.loads(compared["chosen"].read_text())
    assert result["expected_next_run"]["fit_would_choose_p"] == chosen["p"] == 0
    assert result["fit_model"]["ridge_alpha"] == chosen["ridge_alpha"] > 0
    assert result["fit_model"]["fast_response"] and "fast_response" in chosen["training"]
    replayed = run_json(capsys, "replay", compared["chosen"], "--data", CLEAN)
    row = row_of(result, "fit", "validation_timing")
    assert row["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)
    assert row["max_um"] == pytest.approx(replayed["max_um"], rel=0, abs=1e-6)
    assert row["ridge_alpha"] == chosen["ridge_alpha"]
    assert abs(row_of(result, "mlr", "validation_timing")["rms_um"] - row["rms_um"]) > 1e-3  # another model


def test_compare_prints_the_model_fit_writes_as_a_column_of_its_own(compared, tmp_path, capsys):
    capsys.readouterr()
    args = ["compare", "--data", MODELLING, "--validate", CLEAN, "--pmax", "1", "--out", tmp_path]
    assert main([str(a) for a in [*args, "--quiet"]]) == 0
    printed = capsys.readouterr().out
    header = next(line for line in printed.splitlines() if line.startswith("RMS µm"))
    assert header.split()[header.split().index("MLR") + 1] == "fit's"
    assert "fit's model (its column above): fit's choice p = 0 as fit writes it (ridge penalty alpha = " in printed


def test_compare_reads_a_validation_run_with_a_sensor_dropout_as_replay_does(compared, capsys):
    """T3 empty on 16 rows of a validation run: compare refused it ("a model can only be fitted on finite
    values"); it is replayed: 3 samples held, 13 in sensor fault and not scored, for every model, and each
    model file's figure is replay's on that run."""
    result, faulty = compared["compare"], compared["faulty"]
    for model, path in (("fit", compared["chosen"]), ("mlr", compared["mlr"])):
        replayed = run_json(capsys, "replay", path, "--data", faulty)
        assert replayed["faults"]["sensor_fault_samples"] == 16 - HOLD_SAMPLES
        row = row_of(result, model, "dropout")
        assert row["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)
        assert row["R_um"] == pytest.approx(replayed["R_um"], rel=0, abs=1e-6)
    assert all(np.isfinite(r["rms_um"]) for r in result["rows"] if r["run"] == "dropout")
    note = next(n for n in result["notes"] if n.startswith("dropout: "))
    assert "T3 not finite (NaN or ±inf) on 16 sample(s)" in note
    assert "T_amb not finite (NaN or ±inf) on 2 sample(s)" in note
    assert f"{16 - HOLD_SAMPLES} sample(s) in sensor fault are not scored" in note
    assert f"{HOLD_SAMPLES + 2} on held readings are" in note


def test_a_modelling_run_with_a_dropout_is_still_refused(tmp_path, capsys):
    faulty = with_dropouts(MODELLING, tmp_path / "dropout.csv", "T3", 200, 16)
    capsys.readouterr()
    assert main(["compare", "--data", str(faulty), "--validate", str(CLEAN), "--out", str(tmp_path)]) == 2
    assert "a model can only be fitted on finite values" in capsys.readouterr().err


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("diagnosed")
    faulty = with_dropouts(DATASETS / "diag_speed_validate.csv", tmp / "dropout.csv", "T1", 300, 20)
    fit = ["fit", "--data", DATASETS / "diag_speed_model.csv", "--temps", "T1,T2", "--p", "0", "--ridge", "0"]
    assert main([str(a) for a in [*fit, "--recalibrate", "none", "--out", tmp / "m", "--quiet"]]) == 0
    model = tmp / "m" / "model.json"
    diagnose = ["diagnose", model, "--data", DATASETS / "diag_speed_model.csv", "--validate", faulty]
    report = tmp / "diagnose.json"
    args = [*diagnose, "--recalibrate", "none", "--json", report, "--out", tmp / "d"]
    assert main([str(a) for a in args]) == 0
    return {"model": model, "faulty": faulty, "report": json.loads(report.read_text()), "out": tmp / "d"}


def test_diagnose_judges_on_a_validation_run_with_a_dropout_as_replay_scores_it(diagnosed, capsys):
    """diagnose refused the run ("repair or drop those rows"; dropping them breaks the sampling); its
    before and after on it are now replay's of the model and of the augmented model on the same run."""
    report = diagnosed["report"]
    assert report["added"], "the speed effect is found"
    augmented = diagnosed["out"] / "model_augmented.json"
    assert report["model"] == str(augmented)
    models = {"before": diagnosed["model"], "after": augmented}
    assert_judged_as_replayed(capsys, report, models, diagnosed["faulty"], lambda path: 20 - HOLD_SAMPLES)
    note = next(n for n in report["notes"] if n.startswith("dropout: "))
    assert "T1 not finite (NaN or ±inf) on 20 sample(s)" in note
    assert f"{20 - HOLD_SAMPLES} sample(s) in sensor fault are not scored" in note


def test_diagnose_still_refuses_a_modelling_run_with_a_dropout(diagnosed, tmp_path, capsys):
    faulty = with_dropouts(DATASETS / "diag_speed_model.csv", tmp_path / "dropout.csv", "T1", 300, 20)
    capsys.readouterr()
    args = ["diagnose", str(diagnosed["model"]), "--data", str(faulty), "--out", str(tmp_path / "d")]
    assert main(args) == 2
    assert "model input 'T1' is not finite at row 300" in capsys.readouterr().err


@pytest.mark.parametrize(
    "column, value, rows",
    [("T5", np.inf, slice(50, 52)), ("T_amb", np.nan, slice(200, 209))],  # an infinite reading; the reference
)
def test_an_infinite_reading_or_a_reference_dropout_on_a_validation_run_is_scored_as_replay_scores_it(
    tmp_path, capsys, compared, column, value, rows
):
    frame = pd.read_csv(CLEAN)
    frame.loc[rows, column] = value
    frame.to_csv(tmp_path / "faulty.csv", index=False)
    result = run_json(
        capsys,
        "compare",
        "--data",
        MODELLING,
        "--validate",
        tmp_path / "faulty.csv",
        "--pmax",
        "0",
        "--quiet",
        "--out",
        tmp_path / "cmp",
    )
    replayed = run_json(capsys, "replay", compared["chosen"], "--data", tmp_path / "faulty.csv")
    assert row_of(result, "fit", "faulty")["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)
