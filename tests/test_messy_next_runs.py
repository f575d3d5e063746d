"""Messy logs met by every verb: a marker in a heat column, an overflow in the measured error, a dead input,
a missed sample, a short row, a repeated header, a sensor logged twice, a run shorter than one check."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from statsmodels.stats.diagnostic import acorr_ljungbox
from test_messy_rows import fitted_coefficients

from groupfit.cli import main
from groupfit.metrics import ljung_box
from groupfit.models.mlr import dependent_columns

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
MODELLING = DATASETS / "paper_cycle.csv"
QUICK = ["--reference", "none", "--quiet", "--p", "0", "--ridge", "0", "--recalibrate", "none"]


def cli(*args) -> int:
    return main([str(a) for a in args])


def one_line(capsys) -> str:
    """The one error line on stderr (the progress a slow machine logs while fitting is not one)."""
    err = [line for line in capsys.readouterr().err.strip().splitlines() if not line.startswith("progress ")]
    assert len(err) == 1, err
    return err[0]


@pytest.fixture(scope="module")
def next_run() -> pd.DataFrame:
    return pd.read_csv(DATASETS / "validation_speed.csv")


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("model")
    assert cli("fit", "--data", MODELLING, "--temps", "T1,T2,T3,T4", *QUICK, "--out", folder) == 0
    return folder / "model.json"


def test_compare_holds_the_ar1_state_on_a_heat_reading_not_taken_and_resample_fills_it(tmp_path, next_run, capsys):
    """A marker in the heat column of a validation run: the AR(1) routine holds its state on that sample, as
    replay of an AR(1) model file does, and the note names it; --resample interpolates the reading instead."""
    marked = next_run.astype({"speed_rpm": object})
    marked.loc[50, "speed_rpm"] = "n/a"
    path = tmp_path / "marked.csv"
    marked.to_csv(path, index=False)
    report = tmp_path / "held.json"
    assert (
        cli(
            "compare", "--data", MODELLING, "--validate", path, "--pmax", "0", "--json", report, "--out", tmp_path / "a"
        )
        == 0
    )
    notes = [n for n in json.loads(report.read_text())["notes"] if n.startswith("marked: AR(1) heat column")]
    assert len(notes) == 1 and "'speed_rpm': 1 sample(s) without a reading" in notes[0]
    assert "the AR(1) routine holds its state" in notes[0]
    assert next_run.loc[49, "speed_rpm"] == next_run.loc[51, "speed_rpm"]  # inside a block: interpolation is exact
    clean = tmp_path / "clean.csv"
    next_run.to_csv(clean, index=False)
    rows = []
    for source in (path, clean):
        report = tmp_path / f"{source.stem}.json"
        options = ["--resample", "100", "--pmax", "1", "--quiet", "--json", report, "--out", tmp_path / source.stem]
        assert cli("compare", "--data", MODELLING, "--validate", source, *options) == 0
        rows.append([r for r in json.loads(report.read_text())["rows"] if r["model"] == "ar1"])
    assert rows[0] == [{**r, "run": rows[0][k]["run"]} for k, r in enumerate(rows[1])]


@pytest.mark.parametrize("reading, limit", [(3e38, None), (500.0, "100")])
def test_replay_leaves_an_overflow_of_the_error_unscored_as_an_empty_cell(
    tmp_path, model, next_run, capsys, reading, limit
):
    overflow, empty = next_run.copy(), next_run.copy()
    overflow.loc[100, "error_um"] = reading
    empty.loc[100, "error_um"] = np.nan
    replays = []
    for name, frame in (("overflow", overflow), ("empty", empty)):
        path, report = tmp_path / f"{name}.csv", tmp_path / f"{name}.json"
        frame.to_csv(path, index=False)
        limits = () if limit is None else ("--range-error", limit)
        assert cli("replay", model, "--data", path, "--json", report, *limits) == 0
        replays.append(json.loads(report.read_text()))
    assert replays[0]["rms_um"] == replays[1]["rms_um"] < 1.0
    assert replays[0]["scored_samples"] == replays[1]["scored_samples"] == len(next_run) - 1
    assert f"1 reading(s) of the error beyond ±{float(limit or 1e5):g} µm (row 101" in capsys.readouterr().out
    assert cli("replay", model, "--data", tmp_path / "overflow.csv", "--range-error", "-3") == 2
    assert "--range-error" in one_line(capsys)


def test_a_dead_input_leaves_no_sample_scored_and_says_so_without_a_warning(tmp_path, model, next_run, capsys):
    path = tmp_path / "dead.csv"
    next_run.assign(T2=np.nan).to_csv(path, index=False)
    report = tmp_path / "dead.json"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cli("replay", model, "--data", path, "--probe-every", "1800", "--json", report) == 0
    result = json.loads(report.read_text())
    assert result["rms_um"] is None and result["measured_samples"] == len(next_run)
    assert result["faults"]["sensor_fault_samples"] == len(next_run)
    assert result["probes"]["rms_without_checks_um"] is None
    assert "residual none: no sample scored (every measured sample in sensor fault" in capsys.readouterr().out


def test_a_run_shorter_than_one_check_interval_is_named(tmp_path, model, next_run, capsys):
    path = tmp_path / "short.csv"
    next_run.iloc[:3].to_csv(path, index=False)
    assert cli("replay", model, "--data", path, "--probe-every", "1800") == 2
    assert "--probe-every 1800: the run ends at 200 s, before its first check" in one_line(capsys)


def test_a_missed_sample_is_not_left_to_the_tolerance_and_a_late_one_is(tmp_path, next_run, capsys):
    missed, late = tmp_path / "missed.csv", tmp_path / "late.csv"
    next_run.drop(index=[200]).to_csv(missed, index=False)
    next_run.assign(time_s=next_run["time_s"] + np.where(np.arange(len(next_run)) >= 200, 10.0, 0.0)).to_csv(
        late, index=False
    )
    assert cli("fit", "--data", missed, *QUICK, "--out", tmp_path / "a") == 2
    message = one_line(capsys)
    assert "200 s apart but the period is 100 s" in message and "--period-tolerance" not in message
    assert cli("fit", "--data", missed, *QUICK, "--resample", "100", "--out", tmp_path / "b") == 0
    assert cli("fit", "--data", late, *QUICK, "--out", tmp_path / "c") == 2
    assert "--period-tolerance PERCENT" in one_line(capsys)
    assert cli("fit", "--data", late, *QUICK, "--period-tolerance", "15", "--out", tmp_path / "d") == 0


def test_diagnose_names_a_missing_reference_and_advises_only_options_it_has(tmp_path, next_run, capsys):
    folder = tmp_path / "model"
    assert cli("fit", "--data", MODELLING, "--temps", "T1,T2,T3,T4", "--reference", "T_amb", "--quiet",
               "--p", "0", "--out", folder) == 0  # fmt: skip
    model = folder / "model.json"
    short = next_run.copy()
    short.loc[99, ["T5", "T6", "T_amb", "error_um", "speed_rpm", "spindle_on"]] = np.nan  # a row cut short
    path = tmp_path / "short_row.csv"
    short.to_csv(path, index=False)
    assert cli("diagnose", model, "--data", path, "--out", tmp_path / "d") == 2
    assert "the reference 'T_amb' of model input 'T1' is not finite at row 100" in one_line(capsys)
    stuck = tmp_path / "stuck.csv"
    next_run.assign(T3=21.0).to_csv(stuck, index=False)
    assert cli("diagnose", model, "--data", stuck, "--out", tmp_path / "e") == 2
    message = one_line(capsys)
    assert "'T3' is constant" in message and "(groupfit fit --temps)" in message


def test_a_repeated_header_is_left_out_and_a_restart_behind_it_is_refused(tmp_path, next_run, capsys):
    text = (DATASETS / "validation_speed.csv").read_text().splitlines()
    header, body = text[0], text[1:]
    paused, restarted = tmp_path / "paused.csv", tmp_path / "restarted.csv"
    paused.write_text("\n".join([header, *body[:200], header, *body[200:]]) + "\n")
    restarted.write_text("\n".join([header, *body, header, *body]) + "\n")
    clean = tmp_path / "clean.csv"
    next_run.to_csv(clean, index=False)
    headers_left_out, plain = fitted_coefficients(tmp_path, paused, clean, options=QUICK)
    assert headers_left_out == plain
    assert "1 row(s) repeating the header left out (row 201" in capsys.readouterr().out
    assert cli("fit", "--data", restarted, *QUICK, "--out", tmp_path / "r") == 2
    message = one_line(capsys)
    assert f"starts again at row {len(body) + 1}" in message and "repeating the header left out" in message


def test_a_sensor_logged_twice_is_named_instead_of_tested_and_no_warning_is_printed(tmp_path, next_run, capsys):
    path = tmp_path / "twice.csv"
    next_run.assign(T7=next_run["T3"]).to_csv(path, index=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cli("fit", "--data", path, "--temps", "T1,T2,T3,T7", *QUICK[2:], "--out", tmp_path / "o") == 0
    out = capsys.readouterr()
    assert "tests   none per input: T3, T7 are linearly dependent" in out.out and "Warning" not in out.err


def test_dependent_columns_are_the_support_of_the_null_space():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(200, 4))
    design = np.column_stack([np.ones(200), x])
    names = ["const", "a", "b", "c", "d"]
    assert dependent_columns(design, names) == []
    dependent = design.copy()
    dependent[:, 3] = dependent[:, 1] + 2.0 * dependent[:, 2]  # c = a + 2 b
    assert dependent_columns(dependent, names) == ["a", "b", "c"]
    offset = design.copy()
    offset[:, 4] = 5.0  # a constant input: the intercept again
    assert dependent_columns(offset, names) == ["const", "d"]
    nearly = design.copy()
    nearly[:, 3] = nearly[:, 1] + 1e-3 * rng.normal(size=200)  # correlated, not dependent
    assert dependent_columns(nearly, names) == []


def test_a_time_cell_holding_a_mark_is_quoted(tmp_path, capsys):
    frame = pd.read_csv(MODELLING).astype({"time_s": object})
    frame.loc[199, "time_s"] = "---"
    path = tmp_path / "marked.csv"
    frame.to_csv(path, index=False)
    assert cli("fit", "--data", path, *QUICK, "--out", tmp_path / "o") == 2
    assert "row 200, column 'time_s' holds '---', not a time" in one_line(capsys)


@pytest.mark.parametrize("resample", [[], ["--resample", "100"]])
def test_a_cell_that_is_no_number_is_named_and_never_averaged_as_a_missed_reading(tmp_path, capsys, resample):
    lines = MODELLING.read_text().splitlines()
    cells = lines[51].split(",")
    cells[2] = '"22,08"'  # a decimal comma quoted in a comma-separated table
    lines[51] = ",".join(cells)
    path = tmp_path / "quoted.csv"
    path.write_text("\n".join(lines) + "\n")
    assert cli("fit", "--data", path, *QUICK, *resample, "--out", tmp_path / "o") == 2
    assert "row 51, column 'T2': '22,08' is not a number" in one_line(capsys)


def test_a_short_residual_is_tested_up_to_half_its_length_and_diagnose_takes_a_ten_row_run(tmp_path, capsys):
    residual = np.random.default_rng(0).normal(size=10)
    test = ljung_box(residual)
    assert test["lags"] == 5
    assert test["Q"] == pytest.approx(float(acorr_ljungbox(residual, lags=[5])["lb_stat"].iloc[0]), rel=1e-12)
    assert np.isnan(ljung_box(residual[:3])["Q"])
    assert ljung_box(np.r_[residual, residual[:1]])["lags"] == 10  # eleven samples: the full test, as before
    assert cli("fit", "--data", MODELLING, "--temps", "T1,T2", *QUICK, "--out", tmp_path / "m") == 0
    model = tmp_path / "m" / "model.json"  # three coefficients: seven samples are enough to diagnose it
    for rows, status in ((10, 0), (6, 2)):
        path = tmp_path / f"rows{rows}.csv"
        pd.read_csv(DATASETS / "validation_speed.csv").iloc[:rows].to_csv(path, index=False)
        capsys.readouterr()
        assert cli("diagnose", model, "--data", path, "--out", tmp_path / f"d{rows}") == status
    assert "6 sample(s) in all; diagnose refits the model's 3 coefficients" in one_line(capsys)


def test_a_next_run_naming_the_inputs_in_another_case_is_told_which_column_to_rename(tmp_path, model, next_run, capsys):
    path = tmp_path / "lower.csv"
    next_run.rename(columns={"T1": "t1", "T2": "t2"}).to_csv(path, index=False)
    assert cli("replay", model, "--data", path) == 2
    assert "column 'T1' not found ('t1' differs only in case or spaces: rename it 'T1')" in one_line(capsys)


def test_a_period_of_hours_asks_whether_the_time_is_in_seconds(tmp_path, next_run, capsys):
    in_ms, plain = tmp_path / "in_ms.csv", tmp_path / "plain.csv"
    next_run.assign(time_s=next_run["time_s"] * 1000.0).to_csv(in_ms, index=False)  # ms under a name in s
    next_run.to_csv(plain, index=False)
    for path in (in_ms, plain):
        assert cli("fit", "--data", path, *QUICK, "--out", tmp_path / path.stem) == 0
    out = capsys.readouterr().out
    assert "in_ms.csv: one sample every 100000 s (27.8 h) in column 'time_s': if its unit is not seconds" in out
    assert "plain.csv: one sample every" not in out
