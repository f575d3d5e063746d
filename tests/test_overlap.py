"""Two logs that overlap (the later one's first rows repeat the earlier one's last) are refused as two runs, and
replay says so of a next run whose clock starts inside the modelling file's."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.overlap import repeated_rows

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
TEMPS = ["T1", "T2"]


@pytest.fixture
def overlapping(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.iloc[:300].to_csv(tmp_path / "first.csv", index=False)
    frame.iloc[260:].to_csv(tmp_path / "second.csv", index=False)  # rows 261-300 in both
    frame.iloc[300:].to_csv(tmp_path / "rest.csv", index=False)  # goes on from the first, no row shared
    return tmp_path


@pytest.mark.parametrize("shared", [0, 1, 2, 40, 299])
def test_the_repeated_rows_are_counted_as_a_brute_force_match_counts_them(shared):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    earlier = load_run(frame.iloc[:300], temps=TEMPS, name="a")
    later = load_run(frame.iloc[300 - shared :], temps=TEMPS, name="b")
    rows = lambda run: [tuple(r) for r in pd.DataFrame(run.temps).assign(e=run.error).to_numpy()]  # noqa: E731
    brute = max((k for k in range(1, 301) if rows(earlier)[-k:] == rows(later)[:k]), default=0)
    assert repeated_rows(earlier, later) == brute == shared


@pytest.mark.parametrize("verb", ["fit", "compare", "diagnose"])
def test_overlapping_logs_are_refused_naming_both_files_and_the_rows(overlapping, capsys, verb):
    first, second = overlapping / "first.csv", overlapping / "second.csv"
    if verb == "diagnose":
        assert main(["fit", "--data", str(first), "--temps", "T1,T2", "--p", "0", "--out", str(overlapping / "m")]) == 0
        argv = ["diagnose", str(overlapping / "m" / "model.json"), "--data", str(first), "--validate", str(second)]
    elif verb == "compare":
        argv = ["compare", "--data", str(first), "--validate", str(second), "--temps", "T1,T2", "--pmax", "0"]
    else:
        argv = ["fit", "--data", str(first), str(second), "--temps", "T1,T2", "--p", "0"]
    capsys.readouterr()
    assert main([*argv, "--out", str(overlapping / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "its first 40 rows repeat the last 40 rows of" in err[0] and "first.csv" in err[0]
    assert not (overlapping / "out").exists()


def test_logs_that_go_on_from_each_other_are_joined(overlapping, capsys):
    argv = ["fit", "--data", str(overlapping / "first.csv"), str(overlapping / "rest.csv"), "--temps", "T1,T2"]
    assert main([*argv, "--p", "0", "--out", str(overlapping / "out")]) == 0


def test_replay_says_a_next_run_overlaps_the_modelling_file(overlapping, capsys):
    argv = ["fit", "--data", str(overlapping / "first.csv"), "--temps", "T1,T2", "--p", "0"]
    assert main([*argv, "--out", str(overlapping / "m")]) == 0
    report = overlapping / "r.json"
    replay = ["replay", str(overlapping / "m" / "model.json"), "--data", str(overlapping / "second.csv")]
    assert main([*replay, "--json", str(report)]) == 0
    out = capsys.readouterr().out
    assert "inside the modelling file first.csv" in out and "the two overlap" in out
    assert json.loads(report.read_text())["continues"] == []
