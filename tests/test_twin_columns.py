"""Input columns that read the same on every row (one channel logged twice) are named in a note and kept."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.twin_columns import twin_columns

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"


def test_twins_are_the_columns_equal_on_every_row_as_a_pairwise_comparison_finds_them():
    rng = np.random.default_rng(3)
    values = rng.normal(20.0, 1.0, (200, 9)).round(1)
    values[:, 4] = values[:, 1]
    values[:, 7] = values[:, 1]
    values[:, 5] = values[:, 2]
    values[10, 5] = np.nan  # one missed reading on one twin only: no longer alike
    values[:, 8] = values[:, 0]
    values[40, 0], values[40, 8] = 0.0, -0.0  # equal readings, whatever their sign bit
    values[30, [0, 8]] = np.nan  # missed on both: still alike
    names = [f"T{k}" for k in range(9)]
    pairs = {
        (names[a], names[b])
        for a in range(9)
        for b in range(a + 1, 9)
        if np.array_equal(values[:, a], values[:, b], equal_nan=True)
    }
    twins = twin_columns(names, values)
    assert {(a, b) for group in twins for i, a in enumerate(group) for b in group[i + 1 :]} == pairs
    assert twin_columns(names, values) == [("T0", "T8"), ("T1", "T4", "T7")]


def test_fit_names_a_channel_logged_twice_and_keeps_both(tmp_path, capsys):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv").assign(T7=lambda f: f["T2"])
    path = tmp_path / "twice.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "m"
    assert main(["fit", "--data", str(path), "--p", "0", "--recalibrate", "none", "--quiet", "--out", str(out)]) == 0
    report = capsys.readouterr()
    assert "input columns that read the same on every row: 'T2' = 'T7'" in report.out + report.err
    model = json.loads((out / "model.json").read_text())
    assert {"T2", "T7"} <= set(model["temps"])


@pytest.mark.parametrize("row", [0, 500])
def test_columns_that_differ_on_one_row_are_not_twins(row):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv").assign(T7=lambda f: f["T2"])
    assert "'T2' = 'T7'" in " ".join(load_run(frame, temps=["T1", "T2", "T7"], name="twice").notes)
    frame.loc[row, "T7"] += 0.01
    run = load_run(frame, temps=["T1", "T2", "T7"], name="near")
    assert "read the same on every row" not in " ".join(run.notes)
