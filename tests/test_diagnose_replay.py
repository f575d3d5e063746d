"""Diagnose scores a grouped model as the controller runs it: its "before" is replay's RMS on the same run.

A p = 3 model fitted on the FE cycle is diagnosed on a repeat of it with
another ambient temperature. Replayed by the run-time rule, it switches where
the criterion says and moves over each switch by the bumpless transfer; the
diagnosis's residual is that replay's, so its RMS before any change equals
``groupfit replay``'s, while the same groups switched hard would score
otherwise.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.fast_response import without_stage
from groupfit.model import ModelFile
from groupfit.runtime import replay_groups

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
TEMPS = "T1,T2"


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    out = tmp_path_factory.mktemp("fit")
    fit = ["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--temps", TEMPS, "--p", "3", "--n", "3"]
    assert main([*fit, "--search", "exact", "--reference", "none", "--quiet", "--out", str(out)]) == 0
    return out / "model.json"


def json_of(capsys, *args) -> dict:
    capsys.readouterr()
    assert main([str(a) for a in args]) == 0
    return json.loads(capsys.readouterr().out)


def test_diagnose_before_is_the_replay_rms_on_the_same_run(fitted, capsys, tmp_path):
    run_path = DATASETS / "repeat_ambient25.csv"
    # diagnose sets a fast-response stage aside: its "before" is the model without it, replayed
    model = without_stage(ModelFile.load(fitted))
    model.save(tmp_path / "base.json")
    replayed = json_of(capsys, "replay", tmp_path / "base.json", "--data", run_path, "--json", "-")
    diagnosed = json_of(capsys, "diagnose", fitted, "--data", run_path, "--json", "-", "--out", tmp_path / "d")
    before = diagnosed["before"]["data"]["rms_um"]
    assert before == pytest.approx(replayed["rms_um"], rel=0, abs=1e-9)
    # the check can fail: the rule's groups switched hard score otherwise
    run = load_run(run_path, temps=list(model.temps))
    inputs = model.inputs(run.frame, run.source)
    switched_hard = run.error - model.predict(inputs, replay_groups(model, inputs))
    assert len(set(replay_groups(model, inputs))) == 4
    assert abs(np.sqrt(np.mean(switched_hard**2)) - before) > 1e-6


def test_diagnose_scores_a_run_beyond_the_clamp_as_replay_does(tmp_path, capsys):
    """A next run 2.2 times as hot as the modelling run drives the prediction beyond the compensation's clamp
    (twice the modelling run's largest): the controller corrects up to the clamp, and the diagnosis's figures
    on that run are replay's, with a note, not those of the unclamped prediction."""
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    hot = frame.copy()
    for column in ("T1", "T2"):
        hot[column] = frame["T_amb"] + 2.2 * (frame[column] - frame["T_amb"])  # within the readings' valid range
    hot["error_um"] = 2.2 * frame["error_um"]
    hot.to_csv(tmp_path / "hot.csv", index=False)
    fit = ["fit", "--data", DATASETS / "paper_cycle.csv", "--temps", TEMPS, "--p", "0", "--recalibrate", "none"]
    assert main([str(a) for a in [*fit, "--quiet", "--out", tmp_path / "m"]]) == 0
    model = tmp_path / "m" / "model.json"
    replayed = json_of(capsys, "replay", model, "--data", tmp_path / "hot.csv", "--json", "-")
    diagnosed = json_of(
        capsys,
        "diagnose",
        model,
        "--data",
        DATASETS / "paper_cycle.csv",
        "--validate",
        tmp_path / "hot.csv",
        "--recalibrate",
        "none",
        "--json",
        "-",
        "--out",
        tmp_path / "d",
    )
    clamp = ModelFile.load(model).switching.comp_max_um
    run_error = hot["error_um"].to_numpy()
    inputs = ModelFile.load(model).inputs(hot, "hot")
    prediction = ModelFile.load(model).predict(inputs)
    assert np.sum(np.abs(prediction) > clamp) > 20  # the clamp binds on this run
    assert replayed["scored_samples"] == len(hot) and replayed["clamped_samples"] > 20  # no reading in fault
    unclamped = float(np.sqrt(np.mean((run_error - prediction) ** 2)))
    before = diagnosed["before"]["validate"]["rms_um"]
    assert before == pytest.approx(replayed["rms_um"], rel=1e-9) and abs(before - unclamped) > 0.1
    assert any("compensation's clamp" in note for note in diagnosed["notes"])


def test_the_augmented_model_keeps_the_span_of_its_inputs_derived_ones_included(tmp_path, capsys):
    """replay tells a run that leaves the modelling range by the model file's input span: the augmented model
    holds it for every input it reads, the effect diagnose added included."""
    fit = ["fit", "--data", DATASETS / "paper_cycle.csv", "--temps", TEMPS, "--p", "0", "--recalibrate", "none"]
    assert main([str(a) for a in [*fit, "--quiet", "--out", tmp_path / "m"]]) == 0
    diagnose = ["diagnose", tmp_path / "m" / "model.json", "--data", DATASETS / "paper_cycle.csv"]
    assert main([str(a) for a in [*diagnose, "--recalibrate", "none", "--out", tmp_path / "d"]]) == 0
    augmented = ModelFile.load(tmp_path / "d" / "model_augmented.json")
    assert augmented.derived_inputs  # an effect was added
    inputs = augmented.inputs(pd.read_csv(DATASETS / "paper_cycle.csv"), "paper_cycle")
    span = dict(augmented.training["input_span"])
    ambient = pd.read_csv(DATASETS / "paper_cycle.csv")[augmented.reference]  # the reference's own span besides
    assert span.pop(augmented.reference) == pytest.approx([ambient.min(), ambient.max()])
    assert list(span) == list(augmented.temps)
    assert np.array(list(span.values())) == pytest.approx(np.column_stack([inputs.min(axis=0), inputs.max(axis=0)]))
