"""What a refusal of a log's missing readings or columns advises is what lets the log be read."""

from pathlib import Path

import pandas as pd
import pytest

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


def test_a_sensor_silent_longer_than_resampling_bridges_is_advised_to_split_and_the_split_runs_fit(tmp_path, capsys):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.loc[100:109, "T1"] = float("nan")  # ten readings in a row: more than --resample interpolates
    frame.to_csv(tmp_path / "dropout.csv", index=False)
    argv = ["fit", "--temps", "T1,T2", "--resample", "100", "--out", str(tmp_path / "o")]
    assert main([*argv, "--data", str(tmp_path / "dropout.csv")]) == 2
    err = capsys.readouterr().err
    assert "rows 101-110 miss 10 readings in a row" in err and "(--data A B, a global model)" in err
    assert "interpolate up to 3 missed readings" not in err
    frame.iloc[:100].to_csv(tmp_path / "a.csv", index=False)
    frame.iloc[110:].to_csv(tmp_path / "b.csv", index=False)
    assert main([*argv, "--quiet", "--data", str(tmp_path / "a.csv"), str(tmp_path / "b.csv")]) == 0


@pytest.mark.parametrize("rows, end", [(slice(0, 9), "start"), (slice(522, 531), "end")])
def test_a_silence_at_either_end_is_advised_to_be_dropped(tmp_path, capsys, rows, end):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.loc[rows, "T1"] = float("nan")
    frame.loc[100:101, "T1"] = float("nan")  # a short gap first: the long one decides the advice
    frame.to_csv(tmp_path / "ends.csv", index=False)
    assert main(["fit", "--data", str(tmp_path / "ends.csv"), "--temps", "T1,T2", "--out", str(tmp_path / "o")]) == 2
    assert (
        f"miss 10 readings in a row, more than --resample SECONDS interpolates (3): drop those rows at the run's {end}"
        in capsys.readouterr().err
    )


def test_a_short_gap_is_still_advised_to_be_interpolated(tmp_path, capsys):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.loc[100:101, "T1"] = float("nan")
    frame.to_csv(tmp_path / "gap.csv", index=False)
    assert main(["fit", "--data", str(tmp_path / "gap.csv"), "--temps", "T1,T2", "--out", str(tmp_path / "o")]) == 2
    assert "let --resample SECONDS interpolate up to 3 missed readings" in capsys.readouterr().err


def test_a_replayed_run_whose_sensor_was_renamed_is_told_which_column_it_may_be(tmp_path, capsys):
    out = tmp_path / "model"
    assert main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--p", "0", "--quiet", "--out", str(out)]) == 0
    frame = pd.read_csv(DATASETS / "validation_timing.csv").rename(columns={"T2": "T2_spindle"})
    frame.to_csv(tmp_path / "next.csv", index=False)
    assert main(["replay", str(out / "model.json"), "--data", str(tmp_path / "next.csv")]) == 2
    assert (
        "column 'T2' not found ('T2_spindle' may be it under another name: rename it 'T2')" in capsys.readouterr().err
    )
    frame.rename(columns={"T2_spindle": "T2"}).to_csv(tmp_path / "next.csv", index=False)
    assert main(["replay", str(out / "model.json"), "--data", str(tmp_path / "next.csv")]) == 0
