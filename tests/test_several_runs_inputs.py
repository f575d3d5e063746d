"""Several runs given to fit as users give them: one too short to fit on alone, one without the ambient column,
one with a stuck sensor, one with a gap in its reference, one saved again; and the glitch note of a replay."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC

from groupfit.cli import main
from groupfit.controller_limits import check_st_name
from groupfit.errors import InputError
from groupfit.glitches import scored_glitches

DATASETS = SYNTHETIC.parent


def fit_json(tmp_path, *paths, extra=()) -> tuple[int, dict]:
    out = tmp_path / "fit.json"
    args = ["fit", "--data", *map(str, paths), "--out", str(tmp_path / "m"), "--json", str(out), "--quiet", *extra]
    code = main([*args, "--recalibrate", "none"])
    return code, (json.loads(out.read_text()) if code == 0 else {})


def test_a_run_the_others_cannot_be_fitted_without_is_not_held_out(tmp_path, capsys):
    paper = pd.read_csv(DATASETS / "paper_cycle.csv")
    short = pd.read_csv(DATASETS / "repeat_warm.csv").iloc[:15]  # fewer samples than fit takes for 7 coefficients
    short.to_csv(tmp_path / "short.csv", index=False)
    paper.to_csv(tmp_path / "paper.csv", index=False)
    code, result = fit_json(tmp_path, tmp_path / "short.csv", tmp_path / "paper.csv")
    assert code == 0
    out = capsys.readouterr().out
    assert "paper not held out: the other runs alone are too short" in out
    assert "leave-one-run-out over 1 run," in result["expected_next_run_method"]
    model = json.loads((tmp_path / "m" / "model.json").read_text())
    standard_errors = [c["mse_standard_error_um2"] for c in model["training"]["model_choice"]["candidates"]]
    assert standard_errors == [None]  # one fold: no spread to take, and the file stays strict JSON
    # the figure is the short run held out, a model of the paper cycle replayed over it: no longer the 5 µm of a
    # model fitted on 15 samples replayed over the paper cycle
    low, high = result["expected_next_run_range_um"]
    assert low <= result["expected_next_run_rms_um"] <= high and high < 1.0


def test_a_run_without_the_ambient_column_is_named(tmp_path, capsys):
    paper = pd.read_csv(DATASETS / "paper_cycle.csv")
    warm = pd.read_csv(DATASETS / "repeat_warm.csv")
    paper.to_csv(tmp_path / "paper.csv", index=False)
    warm.drop(columns=["T_amb"]).to_csv(tmp_path / "noamb.csv", index=False)
    code, result = fit_json(tmp_path, tmp_path / "paper.csv", tmp_path / "noamb.csv")
    model = json.loads((tmp_path / "m" / "model.json").read_text())
    assert code == 0 and model.get("reference") is None  # absolute readings: no reference key
    assert "noamb.csv: no T_amb column, which the other runs have" in capsys.readouterr().out
    code, _ = fit_json(tmp_path, tmp_path / "paper.csv", tmp_path / "noamb.csv", extra=("--reference", "T_amb"))
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("groupfit fit: error: ") and "noamb.csv: no column 'T_amb'" in err
    assert "paper.csv" not in err and len(err.splitlines()) == 1


def test_a_sensor_stuck_in_one_run_leaves_the_inputs_every_run_shares(tmp_path, capsys):
    paper = pd.read_csv(DATASETS / "paper_cycle.csv")
    stuck = pd.read_csv(DATASETS / "repeat_timing.csv")
    stuck["T3"] = stuck["T3"].iloc[0]
    paper.to_csv(tmp_path / "paper.csv", index=False)
    stuck.to_csv(tmp_path / "stuck.csv", index=False)
    for order in ((tmp_path / "paper.csv", tmp_path / "stuck.csv"), (tmp_path / "stuck.csv", tmp_path / "paper.csv")):
        code, result = fit_json(tmp_path, *order)
        assert code == 0
        assert "T3" not in result["temps"] and {"T1", "T2", "T4", "T5", "T6"} <= set(result["temps"])
        out = capsys.readouterr().out
        assert "T3 left out of the inputs of every run: loading left it out of " in out and "stuck.csv (see" in out


def test_a_gap_in_one_runs_reference_is_named_by_its_own_row(tmp_path, capsys):
    paper = pd.read_csv(DATASETS / "paper_cycle.csv")
    gap = pd.read_csv(DATASETS / "repeat_warm.csv")
    gap.loc[100:130, "T_amb"] = np.nan
    paper.to_csv(tmp_path / "paper.csv", index=False)
    gap.to_csv(tmp_path / "gap.csv", index=False)
    code, _ = fit_json(tmp_path, tmp_path / "paper.csv", tmp_path / "gap.csv")
    err = capsys.readouterr().err.strip()
    assert code == 2 and "gap.csv: row 101, column 'T_amb'" in err and "paper.csv" not in err


def test_a_run_saved_again_is_not_a_run_of_its_own(tmp_path, capsys):
    paper = pd.read_csv(DATASETS / "paper_cycle.csv")
    paper.to_csv(tmp_path / "paper.csv", index=False)
    (tmp_path / "paper_crlf.csv").write_bytes((tmp_path / "paper.csv").read_bytes().replace(b"\n", b"\r\n"))
    pd.read_csv(DATASETS / "repeat_warm.csv").to_csv(tmp_path / "warm.csv", index=False)
    paths = (tmp_path / "paper.csv", tmp_path / "warm.csv", tmp_path / "paper_crlf.csv")
    code, _ = fit_json(tmp_path, *paths)
    err = capsys.readouterr().err.strip()
    assert code == 2 and "paper_crlf.csv: every reading repeats " in err and "paper.csv, given as data" in err
    assert len(err.splitlines()) == 1


def test_a_glitch_on_a_sample_in_sensor_fault_is_not_named_as_scored():
    error = np.sin(np.linspace(0, 3, 200))
    error[100] += 5.0  # a glitch
    residual = error - np.sin(np.linspace(0, 3, 200))
    scored, notes = scored_glitches(error, residual)
    assert scored["glitch_rows"] == [101] and notes
    residual[98:104] = np.nan  # the replay's sensor fault there: not scored
    assert scored_glitches(error, residual) == ({}, [])


@pytest.mark.parametrize("name", ["TO_REAL", "to_lreal", "LREAL_TO_REAL", "DINT_TO_REAL", "REAL_TO_BCD"])
def test_a_block_named_as_a_type_conversion_is_refused(name):
    with pytest.raises(InputError, match="reserved word"):
        check_st_name(name)
    check_st_name("TOTAL_COMP")


def test_compare_names_the_run_without_the_ambient_column(tmp_path, capsys):
    pd.read_csv(DATASETS / "paper_cycle.csv").to_csv(tmp_path / "paper.csv", index=False)
    pd.read_csv(DATASETS / "repeat_warm.csv").drop(columns=["T_amb"]).to_csv(tmp_path / "noamb.csv", index=False)
    args = ["compare", "--data", str(tmp_path / "paper.csv"), str(tmp_path / "noamb.csv"), "--quiet"]
    assert main([*args, "--out", str(tmp_path / "c")]) == 0
    assert "noamb.csv: no T_amb column, which the other runs have" in capsys.readouterr().out
