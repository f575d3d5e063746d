"""``groupfit compare`` with several modelling runs after ``--data``: the global models, fitted on them joined."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
TEMPS = ["T1", "T2", "T3", "T4", "T5", "T6"]
MODELLING = [DATASETS / "paper_cycle.csv", DATASETS / "repeat_timing.csv"]
NEXT = DATASETS / "validation_speed.csv"


def inputs(frame: pd.DataFrame) -> np.ndarray:
    """An intercept column and the temperatures over the ambient, as ``fit`` takes them by default."""
    return np.column_stack([np.ones(len(frame)), frame[TEMPS].to_numpy() - frame[["T_amb"]].to_numpy()])


@pytest.fixture(scope="module")
def several(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("several")
    data = ["--data", *map(str, MODELLING)]
    compare = ["compare", *data, "--validate", str(NEXT), "--reference", "T_amb", "--pmax", "2"]
    assert main([*compare, "--json", str(tmp / "compare.json"), "--out", str(tmp / "cmp"), "--quiet"]) == 0
    plain = ["--p", "0", "--recalibrate", "none", "--reference", "T_amb"]  # least squares, no fast stage
    assert main(["fit", *data, *plain, "--out", str(tmp / "ls"), "--quiet"]) == 0
    assert main(["fit", *data, "--reference", "T_amb", "--out", str(tmp / "chosen"), "--quiet"]) == 0
    replay = ["replay", str(tmp / "ls" / "model.json"), "--data", str(NEXT), "--json", str(tmp / "ls.json")]
    assert main(replay) == 0
    replay = ["replay", str(tmp / "chosen" / "model.json"), "--data", str(NEXT), "--json", str(tmp / "chosen.json")]
    assert main(replay) == 0
    return {
        "compare": json.loads((tmp / "compare.json").read_text()),
        "ls": json.loads((tmp / "ls" / "model.json").read_text()),
        "chosen": json.loads((tmp / "chosen" / "model.json").read_text()),
        "replay_ls": json.loads((tmp / "ls.json").read_text()),
        "replay_chosen": json.loads((tmp / "chosen.json").read_text()),
        "figures": sorted(p.name for p in (tmp / "cmp").iterdir()),
    }


def test_the_runs_are_joined_and_only_the_global_models_are_compared(several):
    result = several["compare"]
    assert result["runs"] == ["paper_cycle+repeat_timing", "validation_speed"]
    # no grouped rows, no AR(1) across the joint; fit's model (a fast-response stage here) beside the MLR
    assert {row["model"] for row in result["rows"]} == {"mlr", "fit"}
    assert result["ar1"] is None
    assert any("2 modelling runs joined" in note for note in result["notes"])
    assert "compare_paper_cycle+repeat_timing.png" in several["figures"]


def test_the_mlr_row_is_the_least_squares_fit_on_both_runs_scored_as_replay_scores_it(several):
    frames = [pd.read_csv(path) for path in MODELLING]
    joined = pd.concat(frames)
    beta = np.linalg.lstsq(inputs(joined), joined["error_um"].to_numpy(), rcond=None)[0]
    np.testing.assert_allclose(several["ls"]["coefficients"][0], beta, rtol=1e-8, atol=1e-10)
    row = {(r["model"], r["run"]): r for r in several["compare"]["rows"]}[("mlr", "validation_speed")]
    assert row["rms_um"] == pytest.approx(several["replay_ls"]["rms_um"], rel=1e-9)


def test_the_next_run_figure_leaves_each_run_out_in_turn(several):
    frames = [pd.read_csv(path) for path in MODELLING]
    residuals = []
    for held, kept in ((0, 1), (1, 0)):
        beta = np.linalg.lstsq(inputs(frames[kept]), frames[kept]["error_um"].to_numpy(), rcond=None)[0]
        residuals.append(frames[held]["error_um"].to_numpy() - inputs(frames[held]) @ beta)
    pooled = float(np.sqrt(np.mean(np.concatenate(residuals) ** 2)))
    expected = several["compare"]["expected_next_run"]
    assert [c["p"] for c in expected["candidates"]] == [0]
    assert expected["candidates"][0]["expected_next_run_rms_um"] == pytest.approx(pooled, rel=1e-9)
    assert several["ls"]["training"]["expected_next_run_rms_um"] == pytest.approx(pooled, rel=1e-9)


def test_compare_marks_what_fit_chooses_on_the_same_runs(several):
    expected, chosen = several["compare"]["expected_next_run"], several["chosen"]
    assert expected["fit_would_choose_p"] == chosen["p"] == 0
    ridge = expected["fit_would_choose_ridge"]
    assert ridge["expected_next_run_rms_um"] == pytest.approx(chosen["training"]["expected_next_run_rms_um"], rel=1e-9)


def test_the_fit_row_is_the_model_fit_writes_on_the_same_runs_scored_as_replay_scores_it(several):
    """fit's choice on the joined runs is not the least-squares MLR: its row is the model fit writes, with the
    penalty and the stage fit gives it, and its figure on the next run is replay's of that model file."""
    result, chosen = several["compare"], several["chosen"]
    assert result["fit_model"]["ridge_alpha"] == (chosen.get("ridge_alpha") or 0.0)
    assert bool(result["fit_model"]["fast_response"]) == ("fast_response" in chosen["training"])
    row = {(r["model"], r["run"]): r for r in result["rows"]}[("fit", "validation_speed")]
    assert row["rms_um"] == pytest.approx(several["replay_chosen"]["rms_um"], rel=0, abs=1e-6)
    assert row["max_um"] == pytest.approx(several["replay_chosen"]["max_um"], rel=0, abs=1e-6)


def test_a_run_whose_columns_come_in_another_order_gives_the_same_figures(tmp_path):
    """Every run's inputs are matched by name: the next-run figure (which chooses p, the penalty and the
    filter) and compare's rows do not move when a logger writes its columns in another order."""
    frame = pd.read_csv(MODELLING[1])
    frame[list(reversed(frame.columns))].to_csv(tmp_path / "reversed.csv", index=False)
    figures = {}
    for name, second in (("as_logged", MODELLING[1]), ("reversed", tmp_path / "reversed.csv")):
        data = ["--data", str(MODELLING[0]), str(second), "--reference", "T_amb", "--quiet"]
        assert main(["fit", *data, "--out", str(tmp_path / name)]) == 0
        report = tmp_path / f"{name}.json"
        assert main(["compare", *data, "--out", str(tmp_path / f"c_{name}"), "--json", str(report)]) == 0
        model = json.loads((tmp_path / name / "model.json").read_text())
        expected = json.loads(report.read_text())["expected_next_run"]
        figures[name] = [
            model["training"]["expected_next_run_rms_um"],
            model["recalibration"]["initial_offset_sigma_um"],
            *(candidate["expected_next_run_rms_um"] for candidate in expected["candidates"]),
        ]
    assert figures["reversed"] == pytest.approx(figures["as_logged"], rel=1e-9)  # 35 times apart before
