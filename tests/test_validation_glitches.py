"""A temperature glitch in a validation run is scored as ``replay`` scores it.

A reading that leaves its neighbours and comes back (one sample of T2 at
450 °C, a spike of +15 K, one of the air's temperature the inputs are taken
against) was interpolated from its neighbours when ``compare`` loaded a
validation run, so that its MLR row scored the run on temperatures the
controller never reads, while ``replay`` of the same model file meets the
reading as logged (through the run-time rule: a reading outside its valid
range held, then a sensor fault). A validation run's temperature glitch is
now kept as logged, with a note naming it, and every figure ``compare``
prints for a model file on the run is ``replay``'s of it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from support.validation import assert_judged_as_replayed, run_json

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
MODELLING = DATASETS / "paper_cycle.csv"
NEXT = DATASETS / "repeat_warm.csv"
REFERENCES = {"T_amb": [], "none": ["--reference", "none"]}


def glitched(tmp: Path, name: str, column: str, row: int, value) -> Path:
    frame = pd.read_csv(NEXT)
    frame.loc[row, column] = value(frame.loc[row, column])
    frame.to_csv(tmp / f"{name}.csv", index=False)
    return tmp / f"{name}.csv"


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("glitched")
    return {
        "spike": glitched(tmp, "spike", "T2", 200, lambda t: t + 15.0),  # within the rule's valid range
        "code": glitched(tmp, "code", "T2", 200, lambda t: 450.0),  # plausible, beyond the rule's range
        "air": glitched(tmp, "air", "T_amb", 300, lambda t: t + 15.0),  # the reference the inputs are taken against
    }


@pytest.fixture(scope="module", params=list(REFERENCES))
def case(request, tmp_path_factory, runs) -> dict:
    """For inputs relative to T_amb and as read: the least-squares MLR as ``fit --p 0`` writes it, the grouped
    model of one break as ``fit --p 1`` writes it, the model ``fit`` chooses (compare's "fit's model"), and
    ``compare``'s result on the glitched runs."""
    tmp = tmp_path_factory.mktemp(f"reference_{request.param}")
    flags = REFERENCES[request.param]
    mlr = ["fit", "--data", MODELLING, "--p", "0", "--recalibrate", "none", *flags, "--out", tmp / "mlr", "--quiet"]
    assert main([str(a) for a in mlr]) == 0
    grouped = ["fit", "--data", MODELLING, "--p", "1", "--recalibrate", "none", *flags, "--out", tmp / "grouped"]
    assert main([str(a) for a in [*grouped, "--quiet"]]) == 0
    assert main([str(a) for a in ["fit", "--data", MODELLING, *flags, "--out", tmp / "chosen", "--quiet"]]) == 0
    report = tmp / "compare.json"
    args = ["compare", "--data", MODELLING, "--validate", *runs.values(), "--pmax", "1", *flags]
    assert main([str(a) for a in [*args, "--json", report, "--out", tmp / "cmp", "--quiet"]]) == 0
    return {
        "models": {
            key: tmp / name / "model.json" for key, name in (("mlr", "mlr"), ("grouped", "grouped"), ("fit", "chosen"))
        },
        "compared": json.loads(report.read_text()),
    }


@pytest.mark.parametrize("run", ["spike", "code", "air"])
def test_compare_scores_a_validation_runs_temperature_glitch_as_replay_does(case, runs, capsys, run):
    """The MLR and the grouped model scored the run on the glitch interpolated (the MLR 0.147 µm RMS where
    replay gives 0.303 µm for the spike), and so did fit's model on a glitch of the reference or of inputs read
    as they are."""
    for model, path in case["models"].items():
        row = next(r for r in case["compared"]["rows"] if r["model"] == model and r["run"] == run and r["p"] < 2)
        replayed = run_json(capsys, "replay", path, "--data", runs[run])
        assert row["rms_um"] == pytest.approx(replayed["rms_um"], rel=1e-9, abs=0)
        assert row["max_um"] == pytest.approx(replayed["max_um"], rel=1e-9, abs=0)
        assert row["R_um"] == pytest.approx(replayed["R_um"], rel=1e-9, abs=0)


def test_the_note_names_the_glitch_as_kept(case):
    notes = case["compared"]["data_notes"]
    note = next(n for n in notes if "spike.csv: 1 temperature reading(s) leave their neighbours" in n)
    assert "('T2' row 201: " in note and "kept as logged" in note and "interpolated" not in note
    assert any("('T_amb' row 301: " in n and "kept as logged" in n for n in notes)


def test_diagnose_judges_on_a_validation_runs_temperature_glitch_as_replay_scores_it(tmp_path, runs, capsys):
    """diagnose scored the run as replay does, its note saying the glitch was interpolated; it now says what
    was scored."""
    fit = ["fit", "--data", MODELLING, "--p", "0", "--recalibrate", "none", "--reference", "none"]
    assert main([str(a) for a in [*fit, "--out", tmp_path / "m", "--quiet"]]) == 0
    model = tmp_path / "m" / "model.json"
    report = tmp_path / "diagnose.json"
    args = ["diagnose", model, "--data", MODELLING, "--validate", runs["spike"], "--recalibrate", "none"]
    capsys.readouterr()
    assert main([str(a) for a in [*args, "--json", report, "--out", tmp_path / "d", "--quiet"]]) == 0
    noted = [line for line in capsys.readouterr().out.splitlines() if "('T2' row 201: " in line]
    assert len(noted) == 1 and "kept as logged" in noted[0] and "interpolated" not in noted[0]
    judged = json.loads(report.read_text())
    assert_judged_as_replayed(capsys, {"before": judged["before"]}, {"before": model}, runs["spike"], lambda _: 0)


@pytest.fixture(scope="module")
def continued(tmp_path_factory) -> dict:
    """The modelling run cut in two, a spike of the air's temperature (the inputs' reference) three samples before
    the end of the first part, the rest continuing its clock; the models as ``fit`` writes them from the first
    part, and ``compare``'s result on the rest."""
    tmp = tmp_path_factory.mktemp("continued")
    frame = pd.read_csv(MODELLING)
    first, rest = frame.iloc[:400].copy(), frame.iloc[400:]
    first.loc[396, "T_amb"] += 4.0
    first.to_csv(tmp / "first.csv", index=False)
    rest.to_csv(tmp / "rest.csv", index=False)
    fits = {"mlr": ["--p", "0", "--recalibrate", "none"], "grouped": ["--p", "1", "--recalibrate", "none"], "fit": []}
    for key, flags in fits.items():
        assert main([str(a) for a in ["fit", "--data", tmp / "first.csv", *flags, "--out", tmp / key, "--quiet"]]) == 0
    report = tmp / "compare.json"
    args = ["compare", "--data", tmp / "first.csv", "--validate", tmp / "rest.csv", "--pmax", "1", "--json", report]
    assert main([str(a) for a in [*args, "--out", tmp / "cmp", "--quiet"]]) == 0
    models = {key: tmp / key / "model.json" for key in fits}
    return {"first": tmp / "first.csv", "rest": tmp / "rest.csv", "models": models, "report": report}


def test_compare_puts_the_modelling_run_as_logged_in_front_of_a_run_that_continues_it(continued, capsys):
    """A run that continues the modelling run is judged with it in front, as replay replays it after the modelling
    file; a temperature glitch of the modelling run is interpolated for the fit, but the history in front is the
    file as logged, as the controller met it and replay reads it: fit's model, whose fast response low-passes each
    input, scored 0.148 µm RMS on the rest where replay gives 0.162 µm."""
    compared = json.loads(continued["report"].read_text())
    notes = compared["data_notes"]
    assert any("first.csv: 1 temperature reading(s)" in n and "interpolated" in n for n in notes)
    assert any(n.startswith("rest continues first") for n in notes)
    for model, path in continued["models"].items():
        row = next(r for r in compared["rows"] if r["model"] == model and r["run"] == "rest" and r["p"] < 2)
        replayed = run_json(capsys, "replay", path, "--data", continued["rest"])
        assert replayed["history_samples"] == 400
        assert row["rms_um"] == pytest.approx(replayed["rms_um"], rel=1e-9, abs=0)
        assert row["max_um"] == pytest.approx(replayed["max_um"], rel=1e-9, abs=0)
        assert row["R_um"] == pytest.approx(replayed["R_um"], rel=1e-9, abs=0)


def test_diagnose_puts_the_modelling_run_as_logged_in_front_of_a_run_that_continues_it(continued, tmp_path, capsys):
    """diagnose judges the run that continues its modelling run with that run in front as logged, as replay does:
    fit's model, its fast-response stage written as plain low-pass inputs (diagnose would set a recorded stage
    aside), scored 0.148 µm RMS on the rest before and after the effect it adds, where replay gives 0.162 µm."""
    model = json.loads(continued["models"]["fit"].read_text())
    assert model["training"].pop("fast_response")["tau_s"] > 0  # its low-passes are now the model's own inputs
    plain = tmp_path / "plain.json"
    plain.write_text(json.dumps(model))
    report = tmp_path / "diagnose.json"
    args = ["diagnose", plain, "--data", continued["first"], "--validate", continued["rest"], "--recalibrate", "none"]
    thresholds = ["--min-score", "0.05", "--min-effect", "0.02"]  # an effect is added: the model file is augmented
    assert main([str(a) for a in [*args, *thresholds, "--json", report, "--out", tmp_path / "d", "--quiet"]]) == 0
    judged = json.loads(report.read_text())
    assert judged["added"]
    for when, path in {"before": plain, "after": tmp_path / "d" / "model_augmented.json"}.items():
        replayed = run_json(capsys, "replay", path, "--data", continued["rest"])
        assert replayed["history_samples"] == 400
        for figure in ("rms_um", "max_um", "R_um"):
            assert judged[when]["validate"][figure] == pytest.approx(replayed[figure], rel=1e-9, abs=0), (when, figure)
