"""What ``fit`` records of the next-run estimate and of how p was set, when p was not chosen by the estimate:
an error missing on some rows, an in-sample rule, a run too short for the p given, a position model."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

PAPER = Path(__file__).resolve().parents[1] / "datasets" / "paper_cycle.csv"
QUIET = ("--quiet", "--recalibrate", "none")


def fit_json(folder: Path, data: Path, *options: str) -> tuple[dict, dict]:
    """``fit --json`` and the model file of ``fit --data DATA OPTIONS``, written under ``folder``."""
    folder.mkdir(exist_ok=True)
    out = folder / "m"
    assert main(["fit", "--data", str(data), *options, "--out", str(out), "--json", str(folder / "f.json")]) == 0
    return json.loads((folder / "f.json").read_text()), json.loads((out / "model.json").read_text())


def run_with_a_gap(folder: Path) -> Path:
    """paper_cycle with the error of one row (301) empty."""
    frame = pd.read_csv(PAPER)
    frame.loc[300, "error_um"] = np.nan
    gap = folder / "gap.csv"
    frame.to_csv(gap, index=False)
    return gap


def test_an_error_missing_on_one_row_names_the_p_it_rules_out(tmp_path, capsys):
    gap = run_with_a_gap(tmp_path)
    _, model = fit_json(tmp_path, gap, *QUIET)
    printed = capsys.readouterr().out
    choice = model["training"]["model_choice"]
    assert model["p"] == 0 and choice["rule"] == "the only p the run allows" and choice["not_tried"] == [1, 2, 3]
    assert "531 of 532 rows" in choice["not_tried_reason"]
    p_line = next(line for line in printed.splitlines() if line.startswith("p  "))
    assert p_line.startswith("p       0: p = 1, 2, 3 not tried: the error is measured on 531 of 532 rows")
    assert main(["fit", "--data", str(gap), "--p", "1", "--out", str(tmp_path / "p1"), *QUIET]) == 2  # the truth


@pytest.mark.parametrize(
    "rule, said", [(("bic",), "smallest BIC (in sample)"), (("target", "--p-target", "95%"), "fewest breaks with R <=")]
)
def test_an_in_sample_rule_is_recorded_as_the_rule_that_chose_p(tmp_path, capsys, rule, said):
    data, model = fit_json(tmp_path, PAPER, "--choose", *rule, *QUIET)
    printed = capsys.readouterr().out
    choice = model["training"]["model_choice"]
    assert choice["p"] == model["p"] == data["p_selection"]["p"]
    assert choice["rule"].startswith(said) and f"p auto  {choice['rule']}: p = {model['p']}" in printed


def test_a_p_too_large_for_the_run_keeps_the_estimates_keys_and_says_what_to_change(tmp_path, capsys):
    short = tmp_path / "short.csv"
    pd.read_csv(PAPER).head(120).to_csv(short, index=False)
    data, model = fit_json(tmp_path, short, "--p", "3", *QUIET)
    note = next(line for line in capsys.readouterr().out.splitlines() if "no next-run estimate" in line)
    assert "no model of p = 3 fits" in note and note.endswith("a smaller --p or a longer run gives one")
    assert data["expected_next_run_rms_um"] is None and data["expected_next_run_range_um"] is None
    assert (
        data["expected_next_run_method"].startswith("not estimated: ") and "p = 3" in data["expected_next_run_method"]
    )
    assert "expected_next_run_rms_um" not in model["training"]  # the model file holds numbers or nothing
    smaller, _ = fit_json(tmp_path / "p0", short, "--p", "0", *QUIET)
    assert smaller["expected_next_run_rms_um"] > 0  # the remedy named works


def check_run_table(path: Path) -> None:
    """Check runs at five positions of an axis, the error linear in the position and the temperatures."""
    rng = np.random.default_rng(3)
    rows = []
    for i in range(40):
        t1, t2, amb = 20 + 4 * (1 - np.exp(-i / 12)), 20 + 2 * np.sin(i / 9), 20 + 0.3 * np.sin(i / 15)
        for position in (0.0, 100.0, 200.0, 300.0, 400.0):
            error = 2 * (t1 - 20) + (t2 - 20) + 0.01 * (t1 - 20) * (position - 200) + rng.normal(0, 0.05)
            rows.append((600.0 * i, position, t1, t2, amb, error))
    pd.DataFrame(rows, columns=["time_s", "P_mm", "T1", "T2", "T_amb", "error_um"]).to_csv(path, index=False)


def test_a_position_model_says_what_it_leaves_to_its_defaults(tmp_path, capsys):
    axis = tmp_path / "axis.csv"
    check_run_table(axis)
    data, model = fit_json(tmp_path, axis, "--temps", "T1,T2", "--position", "P_mm", "--quiet")
    note = next(line for line in capsys.readouterr().out.splitlines() if "no next-run estimate" in line)
    assert model["p"] == 0 and model["reference"] == "T_amb"
    assert "p = 0 (--p N" in note and "the reference T_amb (--reference" in note and "are the defaults" in note
    assert data["expected_next_run_rms_um"] is None and data["expected_next_run_method"].startswith("not estimated")
    _, model = fit_json(
        tmp_path / "given", axis, "--temps", "T1,T2", "--position", "P_mm", "--p", "0", "--reference", "none", "--quiet"
    )
    note = next(line for line in capsys.readouterr().out.splitlines() if "no next-run estimate" in line)
    assert model.get("reference") is None and "default" not in note  # nothing left to a default: nothing said of it


def test_compare_names_the_p_its_estimate_could_not_try_as_fit_does(tmp_path, capsys):
    short = tmp_path / "short.csv"
    pd.read_csv(PAPER).head(120).to_csv(short, index=False)
    _, model = fit_json(tmp_path / "fit", short, "--quiet")
    fit_untried = model["training"]["model_choice"]["not_tried"]
    capsys.readouterr()
    out = tmp_path / "c.json"
    assert main(["compare", "--data", str(short), "--pmax", "3", "--out", str(tmp_path / "c"), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    expected = json.loads(out.read_text())["expected_next_run"]
    assert fit_untried and expected["not_tried"] == fit_untried
    assert {row["p"] for row in expected["candidates"]}.isdisjoint(fit_untried)
    listed = ", ".join(str(p) for p in fit_untried)
    assert f"note: p = {listed} not tried, their groups not fitting" in printed


def test_compare_records_the_p_an_unmeasured_row_rules_out_as_fit_does(tmp_path, capsys):
    gap = run_with_a_gap(tmp_path)
    _, model = fit_json(tmp_path / "fit", gap, *QUIET)
    choice = model["training"]["model_choice"]
    out = tmp_path / "c.json"
    assert main(["compare", "--data", str(gap), "--out", str(tmp_path / "c"), "--json", str(out), "--quiet"]) == 0
    expected = json.loads(out.read_text())["expected_next_run"]
    assert expected["not_tried"] == choice["not_tried"] == [1, 2, 3]
    assert expected["not_tried_why"] == f"p = 1, 2, 3 not tried: {choice['not_tried_reason']}"
    assert expected["fit_would_choose_p"] == model["p"] == 0
