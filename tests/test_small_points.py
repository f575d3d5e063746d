"""Smaller points of real logs: table spacing, break lists without conditions, a heater on from the start, a
sample index, an ambient named by flag, a ridge penalty of 0, and a GA result left unchecked."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pandas as pd
from test_real_logs import cycle_means

from groupfit.cli import main
from groupfit.columns import usable_columns
from groupfit.comparison_text import comparison_table
from groupfit.fast_response import without_stage
from groupfit.heldout.folds import operating_columns
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor
from groupfit.search.base import SearchSettings


def cli(*args) -> int:
    return main([str(a) for a in args])


def test_the_comparison_table_never_runs_numbers_together():
    values = {"mlr": 1284.3413, "ar1": 13321.68, "grouped1": 987654.321}
    index = {
        (key, "run"): {"R_um": v, "rms_um": v / 100, "max_um": v / 10, "accuracy_percent": 50.0}
        for key, v in values.items()
    }
    result = SimpleNamespace(runs=["run"], run_conditions={"run": "modelling"}, reference=None)
    lines = comparison_table(result, list(values), index)
    row = next(line for line in lines if line.startswith("run") and "1284.34" in line)
    numbers = [float(token) for token in row.split() if token.replace(".", "").isdigit()]
    assert numbers == [round(v, 2) for v in values.values()]  # each its own token


def test_breaks_without_operating_conditions_print_no_none(tmp_path, capsys):
    path = tmp_path / "printer.csv"
    cycle_means().drop(columns=["bed_target"]).to_csv(path, index=False)
    assert cli("compare", "--data", path, "--pmax", "2", "--heat", "none", "--quiet", "--out", tmp_path) == 0
    report = capsys.readouterr().out
    assert "None" not in report and "no change of operating condition" in report
    # with its heater's set-point logged, the breaks are set against the set-point's changes
    cycle_means().to_csv(path, index=False)
    assert cli("compare", "--data", path, "--pmax", "2", "--heat", "none", "--quiet", "--out", tmp_path) == 0
    report = capsys.readouterr().out
    assert "nearest change of operating condition at [100, 180, 280]" in report


def test_a_heater_on_from_the_start_is_kept_and_a_sample_index_left_out():
    n = 50
    frame = pd.DataFrame(
        {
            "bed_target": np.full(n, 60.0),  # switched on at t = 0, at its set-point
            "dead": np.zeros(n),
            "T_stuck": np.full(n, 25.0),  # a temperature stuck at one value is a dead sensor, not a set-point
            "sample": np.arange(n) + 1.0,
            "clock_s": 5.0 + 30.0 * np.arange(n),
            "speed": np.where(np.arange(n) < 25, 0.0, 3000.0),
            "T_overflow": np.where(np.arange(n) == 7, 1e308, 20.0 + 0.1 * np.arange(n)),  # a logger's marker
        }
    )
    usable, notes = usable_columns(frame, set())
    assert any("'T_overflow' left out: 1e+308 at row 8 is no reading" in note for note in notes)
    assert usable == ["bed_target", "speed"]
    assert any("'bed_target' kept though constant (60)" in note for note in notes)
    assert any("'sample' left out: a sample index" in note for note in notes)
    assert any("'clock_s' left out: a sample index or clock" in note for note in notes)
    assert any("'dead' left out: constant 0" in note for note in notes)
    assert any("'T_stuck' left out: constant 25 (a stuck temperature sensor?)" in note for note in notes)
    assert operating_columns(frame, usable) == ["bed_target", "speed"]  # its lags start from rest


def test_an_ambient_named_by_flag_is_no_input_and_the_reference(tmp_path):
    frame = cycle_means()
    frame["T15"] = 21.0 + 0.3 * np.sin(np.arange(len(frame)) / 40.0)  # the air, named like a sensor
    path = tmp_path / "room.csv"
    frame.to_csv(path, index=False)
    assert cli("fit", "--data", path, "--p", "0", "--json", tmp_path / "a.json", "--out", tmp_path) == 0
    assert json.loads((tmp_path / "a.json").read_text())["temps"] == ["T1", "T2", "T15"]
    assert (
        cli("fit", "--data", path, "--p", "0", "--ambient", "T15", "--json", tmp_path / "b.json", "--out", tmp_path)
        == 0
    )
    model = json.loads((tmp_path / "b.json").read_text())
    choice = model["training"]["reference_choice"]  # the named ambient is the default, questioned as T_amb is
    assert without_stage(ModelFile.from_dict(model)).temps == ("T1", "T2") and choice["default"] == "T15"
    assert model.get("reference") == choice["chosen"] and choice["chosen"] is None  # the error never follows it
    args = ("--data", path, "--p", "0", "--ambient", "T15", "--reference", "T15")
    assert cli("fit", *args, "--json", tmp_path / "c.json", "--out", tmp_path, "--force") == 0
    assert json.loads((tmp_path / "c.json").read_text())["reference"] == "T15"
    assert cli("fit", "--data", path, "--p", "0", "--ambient", "T99", "--out", tmp_path) == 2


def test_ridge_auto_choosing_no_penalty_keeps_the_model(tmp_path, capsys):
    rng = np.random.default_rng(1)
    n = 400
    time = np.round(np.concatenate([[0.0], np.cumsum(rng.uniform(59.3, 60.4, n - 1))]))
    heat = (np.arange(n) % 200 < 120).astype(float)
    t1 = 20 + 0.1 * np.convolve(heat, np.exp(-np.arange(100) / 30), "full")[:n] + rng.normal(0, 0.02, n)
    t2 = 20 + 0.08 * np.convolve(heat, np.exp(-np.arange(100) / 60), "full")[:n] + rng.normal(0, 0.02, n)
    error = 3 * (t1 - 20) + 2 * (t2 - 20) + rng.normal(0, 0.1, n)  # the model is all there is
    frame = pd.DataFrame({"time_s": time, "T1": t1, "T2": t2, "error_um": error})
    path = tmp_path / "linear.csv"
    frame.to_csv(path, index=False)
    assert cli("fit", "--data", path, "--p", "0", "--out", tmp_path, "--quiet") == 0
    out = tmp_path / "d.json"
    args = ("--data", path, "--ridge", "auto", "--json", out, "--out", tmp_path)
    assert cli("diagnose", tmp_path / "model.json", *args) == 0
    report = capsys.readouterr().out
    result = json.loads(out.read_text())
    assert result["ridge"]["alpha"] == 0.0
    assert "the model is kept as given" in report and "not recommended" not in report
    assert result["before"]["data"] == result["after"]["data"]


def test_fit_says_why_a_ga_result_is_not_checked_against_the_exact_optimum():
    rng = np.random.default_rng(0)
    for n, checked in ((400, True), (800, False)):  # sae: N²/2 = 80 000 and 320 000 segment pairs (limit 200 000)
        X = rng.normal(size=(n, 2)).cumsum(axis=0)
        y = X @ [2.0, -1.0] + np.where(np.arange(n) < n // 2, 0.0, 5.0) + rng.normal(0, 0.1, n)
        search = SearchSettings(method="ga", seed=0)
        info = GroupedRegressor.from_settings(p=1, search=search).fit(X, y).search_
        assert ("gap_percent" in info) == checked and ("exact_skipped" in info) != checked
    assert "N = 800 samples give 3.2e+05 segment pairs, over the 2e+05" in info["exact_skipped"]
