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
