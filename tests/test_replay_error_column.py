"""``replay`` on a next run whose log names its error otherwise than the model's run did."""

import json
from pathlib import Path

import pandas as pd
import pytest

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    out = tmp_path_factory.mktemp("model")
    assert main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--p", "1", "--out", str(out), "--quiet"]) == 0
    return out / "model.json"


def replayed(tmp_path, model, frame, *args) -> dict:
    frame.to_csv(tmp_path / "next.csv", index=False)
    assert (
        main(["replay", str(model), "--data", str(tmp_path / "next.csv"), *args, "--json", str(tmp_path / "r.json")])
        == 0
    )
    return json.loads((tmp_path / "r.json").read_text())


def test_the_one_column_named_as_an_error_scores_the_replay_with_a_note(tmp_path, model, capsys):
    frame = pd.read_csv(DATASETS / "repeat_warm.csv")
    reference = replayed(tmp_path, model, frame)
    renamed = replayed(tmp_path, model, frame.rename(columns={"error_um": "Drift [um]"}))
    assert "thermal error from column 'Drift [um]' (there is no 'error_um'" in capsys.readouterr().out
    assert renamed["rms_um"] == reference["rms_um"]
    assert [s["residual_um"] for s in renamed["samples"]] == [s["residual_um"] for s in reference["samples"]]


def test_several_candidates_are_named_and_none_is_guessed(tmp_path, model, capsys):
    frame = pd.read_csv(DATASETS / "repeat_warm.csv").rename(columns={"error_um": "Drift [um]"})
    frame["dZ_um"] = frame["Drift [um]"] + 1.0
    result = replayed(tmp_path, model, frame)
    assert result["rms_um"] is None
    assert "2 could be the error (Drift [um], dZ_um); --error names one" in capsys.readouterr().out
    chosen = replayed(tmp_path, model, frame, "--error", "dZ_um")
    assert chosen["rms_um"] is not None and all(s["residual_um"] is not None for s in chosen["samples"])


def test_an_error_column_asked_for_and_not_in_the_run_is_refused_naming_it(tmp_path, model, capsys):
    pd.read_csv(DATASETS / "repeat_warm.csv").to_csv(tmp_path / "next.csv", index=False)
    args = ["replay", str(model), "--data", str(tmp_path / "next.csv"), "--error", "nosuchcolumn"]
    assert main([*args, "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--error 'nosuchcolumn': no such column" in err[0] and "error_um" in err[0]
    assert not (tmp_path / "r.json").exists()
