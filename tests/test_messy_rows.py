"""Messy next runs and modelling logs: two recordings sorted into one clock, overflow values and
no-reading marks, met the same way by every verb."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support import independent_machine as machine

from groupfit.cli import main
from groupfit.interleaved import interleaved_recordings, stamp_groups

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
TEMPS = "T1,T2,T3,T4"
QUICK = ["--temps", TEMPS, "--reference", "none", "--quiet", "--p", "0", "--ridge", "0", "--recalibrate", "none"]


def cli(*args) -> int:
    return main([str(a) for a in args])


def fitted_coefficients(tmp_path: Path, *sources: Path, options=QUICK) -> list:
    """The coefficients ``fit --json`` gives on each log, in order."""
    coefficients = []
    for source in sources:
        report = tmp_path / f"{source.stem}.json"
        assert cli("fit", "--data", source, *options, "--json", report, "--out", tmp_path / source.stem) == 0
        coefficients.append(json.loads(report.read_text())["coefficients"])
    return coefficients


def sorted_together(first: pd.DataFrame, second: pd.DataFrame, shift_s: float, seed: int) -> pd.DataFrame:
    """Two recordings on one clock (the second shifted by ``shift_s``), rows sorted by time in no stable order."""
    n = min(len(first), len(second))
    joined = pd.concat([first.iloc[:n], second.iloc[:n].assign(time_s=first["time_s"].to_numpy()[:n] + shift_s)])
    shuffled = joined.sample(frac=1.0, random_state=seed)
    return shuffled.sort_values("time_s", kind="quicksort").reset_index(drop=True)


def bins(time: np.ndarray, period_s: float) -> np.ndarray:
    return np.floor((time - time[0]) / period_s + 1e-9).astype(np.int64)


@pytest.fixture(scope="module")
def scenarios():
    return machine.scenarios(["speed_rpm_2h_30s", "amb_T_amb_30s"]) + machine.random_scenarios(6)


def test_every_pair_of_simulated_runs_sorted_together_reads_as_two_recordings(scenarios):
    for k, scenario in enumerate(scenarios):
        log = sorted_together(scenario.modelling, scenario.validation, 0.0, seed=k)
        assert interleaved_recordings(log, stamp_groups(log["time_s"].to_numpy()), time="time_s"), scenario.name
        period = float(np.median(np.diff(scenario.modelling["time_s"])))
        shifted = sorted_together(scenario.modelling, scenario.validation, 0.4 * period, seed=k)
        assert interleaved_recordings(shifted, bins(shifted["time_s"].to_numpy(), period), time="time_s")


def test_no_single_run_reads_as_two_recordings_at_any_resampling(scenarios):
    runs = [run for s in scenarios for run in (s.modelling, s.validation)]
    runs += [pd.read_csv(path) for path in sorted(DATASETS.glob("*.csv"))]
    for run in runs:
        time = run["time_s"].to_numpy(dtype=float)
        period = float(np.median(np.diff(time)))
        for factor in (2, 3, 4, 10):
            assert not interleaved_recordings(run, bins(time, factor * period), time="time_s")


@pytest.mark.parametrize("per_stamp", [2, 3, 10])
@pytest.mark.parametrize("noise", [0.0, 0.05, 1.0])
def test_a_fast_logger_with_a_coarse_clock_is_one_recording(per_stamp, noise):
    rng = np.random.default_rng(per_stamp)
    time = np.arange(0.0, 3600.0, 1.0 / per_stamp)
    warming = 20.0 + 5.0 * (1.0 - np.exp(-time / 900.0))
    log = pd.DataFrame(
        {
            "time_s": np.floor(time),
            "T1": warming + noise * rng.standard_normal(time.size),
            "T2": 1.1 * warming + noise * rng.standard_normal(time.size),
            "error_um": 10.0 * warming + noise * rng.standard_normal(time.size),
        }
    )
    assert not interleaved_recordings(log, stamp_groups(log["time_s"].to_numpy()), time="time_s")
    assert not interleaved_recordings(log, bins(log["time_s"].to_numpy(), 10.0), time="time_s")


@pytest.mark.parametrize("resample", [None, "30", "120"])
def test_fit_refuses_two_sorted_recordings_and_does_not_advise_averaging_them(tmp_path, scenarios, capsys, resample):
    scenario = scenarios[0]
    path = tmp_path / "two_days.csv"
    sorted_together(scenario.modelling, scenario.validation, 0.0, seed=1).to_csv(path, index=False)
    out = tmp_path / "out"
    extra = ["--resample", resample] if resample else []
    assert cli("fit", "--data", path, *QUICK[:2], "--out", out, *extra) == 2
    message = capsys.readouterr().err.strip().splitlines()
    assert len(message) == 1 and "two_days.csv" in message[0] and "two recordings" in message[0]
    assert "--data a.csv b.csv" in message[0] and "--resample" not in message[0]
    assert not out.exists()


def test_a_fast_logger_is_still_averaged_by_resample(tmp_path, capsys):
    rng = np.random.default_rng(5)
    time = np.arange(0.0, 7200.0, 0.5)
    warming = 1.0 - np.exp(-time / 1800.0)
    log = pd.DataFrame(
        {
            "time_s": np.floor(time),
            "T1": 20.0 + 4.0 * warming + 0.05 * rng.standard_normal(time.size),
            "T2": 20.0 + 2.0 * warming**2 + 0.05 * rng.standard_normal(time.size),
        }
    )
    log["error_um"] = 3.0 * (log["T1"] - 20.0) - 2.0 * (log["T2"] - 20.0) + 0.1 * rng.standard_normal(time.size)
    path = tmp_path / "fast.csv"
    log.to_csv(path, index=False)
    report = tmp_path / "fit.json"
    options = ["--p", "0", "--reference", "none", "--resample", "60", "--quiet", "--json", report]
    assert cli("fit", "--data", path, "--temps", "T1,T2", *options, "--out", tmp_path / "out") == 0
    fitted = json.loads(report.read_text())
    assert fitted["n_samples"] == 121  # two hours of 60-s periods, the last one begun
    np.testing.assert_allclose(fitted["coefficients"][0][1:], [3.0, -2.0], atol=0.02)


# ----------------------------------------------------------------- overflow values and no-reading marks


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    folder = tmp_path_factory.mktemp("model")
    assert cli("fit", "--data", DATASETS / "paper_cycle.csv", *QUICK, "--out", folder) == 0
    return folder / "model.json"


def test_diagnose_refuses_an_overflow_value_as_fit_does_and_resample_takes_it_as_missed(tmp_path, model, capsys):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    log.loc[100, "T3"] = 9.9e37
    path = tmp_path / "overflow.csv"
    log.to_csv(path, index=False)
    assert cli("fit", "--data", path, *QUICK, "--out", tmp_path / "fit") == 2
    fit_message = capsys.readouterr().err
    assert cli("diagnose", model, "--data", path, "--out", tmp_path / "diag") == 2
    message = capsys.readouterr().err
    assert "row 101, column 'T3': 9.9e+37 °C is outside the plausible range" in message
    assert message.split(":", 1)[1] == fit_message.split(":", 1)[1]
    assert not (tmp_path / "diag").exists()

    emptied = tmp_path / "emptied.csv"
    log.loc[100, "T3"] = np.nan
    log.to_csv(emptied, index=False)
    reports = []
    for source in (path, emptied):
        report = tmp_path / f"{source.stem}.json"
        options = ["--resample", "100", "--json", report, "--out", tmp_path / source.stem]
        assert cli("diagnose", model, "--data", source, *options) == 0
        reports.append(json.loads(report.read_text()))
    assert reports[0]["before"] == reports[1]["before"] and reports[0]["after"] == reports[1]["after"]


def test_diagnose_takes_a_widened_range(tmp_path, model):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    log.loc[100, "T3"] = 700.0
    path = tmp_path / "hot.csv"
    log.to_csv(path, index=False)
    assert cli("diagnose", model, "--data", path, "--out", tmp_path / "a") == 2
    assert cli("diagnose", model, "--data", path, "--range-temp=-50,800", "--out", tmp_path / "b") == 0


@pytest.mark.parametrize("mark", ["---", "OVL", "ERR", "-"])
def test_a_no_reading_mark_in_a_next_run_is_an_empty_cell_to_replay_and_diagnose(tmp_path, model, capsys, mark):
    log = pd.read_csv(DATASETS / "validation_speed.csv").astype({"T2": object})
    empty = log.copy()
    log.loc[50, "T2"] = mark
    empty.loc[50, "T2"] = np.nan
    marked, emptied = tmp_path / "marked.csv", tmp_path / "emptied.csv"
    log.to_csv(marked, index=False)
    empty.to_csv(emptied, index=False)
    replays = []
    for source in (marked, emptied):
        report = tmp_path / f"{source.stem}.json"
        assert cli("replay", model, "--data", source, "--json", report) == 0
        replays.append(json.loads(report.read_text()))
    assert replays[0]["samples"] == replays[1]["samples"]
    assert replays[0]["rms_um"] == replays[1]["rms_um"] and replays[0]["faults"] == replays[1]["faults"]
    messages = []
    for source in (marked, emptied):
        assert cli("diagnose", model, "--data", source, "--out", tmp_path / "d") == 2
        messages.append(capsys.readouterr().err.split(".csv:", 1)[1])
    assert messages[0] == messages[1] and "row 51" in messages[0]


# ----------------------------------------------------------------- blank rows and rows without a time


def test_blank_spreadsheet_rows_are_left_out_with_a_note_and_change_nothing_else(tmp_path, capsys):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    blank = pd.DataFrame([{column: np.nan for column in log.columns}])
    with_blanks = pd.concat([log.iloc[:199], blank, log.iloc[199:400], blank, blank, log.iloc[400:]])
    path, clean = tmp_path / "blanks.csv", tmp_path / "clean.csv"
    with_blanks.to_csv(path, index=False)
    log.to_csv(clean, index=False)
    blanks_left_out, plain = fitted_coefficients(tmp_path, path, clean)
    assert blanks_left_out == plain
    assert "3 row(s) empty in every column left out (row 200, 402, 403:" in capsys.readouterr().out


def with_lines(tmp_path: Path, name: str, after_row: int, *inserted: str) -> tuple[Path, Path]:
    """The FE modelling run written plainly, and with ``inserted`` lines after its data row ``after_row``."""
    clean = tmp_path / "clean.csv"
    pd.read_csv(DATASETS / "paper_cycle.csv").to_csv(clean, index=False)
    lines = clean.read_text().splitlines()
    path = tmp_path / f"{name}.csv"
    path.write_text("\n".join([*lines[: 1 + after_row], *inserted, *lines[1 + after_row :]]) + "\n")
    return path, clean


SEPARATORS = "," * 10


@pytest.mark.parametrize(
    ("after_row", "inserted", "note"),
    [
        (4, ["", SEPARATORS], "1 row(s) empty in every column left out (row 5:"),
        (60, ["", SEPARATORS], "1 row(s) empty in every column left out (row 61:"),
        (0, [SEPARATORS, SEPARATORS], "2 row(s) empty in every column left out (row 1, 2:"),
        (0, ["-" * 40], ""),
        (0, [",".join(["-----"] * 11)], ""),
        (3, ["Logging paused"], "1 row(s) holding a message alone left out (row 4: a logger's message, such as "),
        (300, ["=" * 20], "1 row(s) holding a message alone left out (row 301: a logger's message, such as '="),
        (300, [",,Pause" + "," * 8], "(row 301: a logger's message, such as 'Pause')"),
        (3, [",,Pause" + "," * 8], "(row 4: a logger's message, such as 'Pause')"),  # the longer body below it
        (30, [",Logging paused" + "," * 9], "(row 31: a logger's message, such as 'Logging paused')"),
    ],
)
def test_blank_rulers_and_message_lines_are_passed_over_and_change_nothing(tmp_path, capsys, after_row, inserted, note):
    path, clean = with_lines(tmp_path, "messy", after_row, *inserted)
    passed_over, plain = fitted_coefficients(tmp_path, path, clean)
    assert passed_over == plain
    assert note in capsys.readouterr().out


def european(line: str, sep: str) -> str:
    """A line of the FE run's CSV as a German logger writes it: decimal commas, ``sep`` between the fields."""
    return sep.join(field.replace(".", ",") for field in line.split(","))


@pytest.mark.parametrize(
    ("sep", "stray", "note"),
    [
        (";", "header", "1 row(s) repeating the header left out (row 301:"),
        (";", "Logging paused", "(row 301: a logger's message, such as 'Logging paused')"),
        ("  ", "Logging paused", "(row 301: a logger's message, such as 'Logging paused')"),
    ],
)
def test_a_stray_row_in_a_table_of_decimal_commas_leaves_its_columns_read_as_numbers(
    tmp_path, capsys, sep, stray, note
):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    log["time_s"] = log["time_s"] + 0.5  # a time column with decimals too
    clean = tmp_path / "clean.csv"
    log.to_csv(clean, index=False)
    lines = [european(line, sep) for line in clean.read_text().splitlines()]
    path = tmp_path / "german.csv"
    path.write_text("\n".join([*lines[:301], lines[0] if stray == "header" else stray, *lines[301:]]) + "\n")
    read, plain = fitted_coefficients(tmp_path, path, clean)
    assert read == plain
    assert note in capsys.readouterr().out


@pytest.mark.parametrize("line", ["Paused at 12:00", "\x00" * 40])  # a digit; nothing legible (a power loss)
def test_a_line_with_a_number_or_nothing_legible_is_refused_naming_its_row(tmp_path, capsys, line):
    path, _ = with_lines(tmp_path, "paused", 300, line)
    assert cli("fit", "--data", path, *QUICK, "--out", tmp_path / "out") == 2
    message = capsys.readouterr().err.strip()
    assert message.endswith(f"row 301, column 'time_s': {line!r} is not a number; fix or remove that row")


@pytest.mark.parametrize("resample", [[], ["--resample", "100"]])
def test_a_row_without_a_time_stamp_is_named_and_not_left_to_resample(tmp_path, capsys, resample):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    log.loc[199, "time_s"] = np.nan
    path = tmp_path / "untimed.csv"
    log.to_csv(path, index=False)
    assert cli("fit", "--data", path, *QUICK, *resample, "--out", tmp_path / "out") == 2
    message = capsys.readouterr().err.strip()
    assert "row 200, column 'time_s' is empty" in message and "--resample" not in message


def test_compare_names_the_input_a_validation_run_lacks(tmp_path, capsys):
    next_run = pd.read_csv(DATASETS / "validation_speed.csv").rename(columns={"T3": "X3"})
    path = tmp_path / "next.csv"
    next_run.to_csv(path, index=False)
    code = cli("compare", "--data", DATASETS / "paper_cycle.csv", "--validate", path, "--out", tmp_path / "out")
    assert code == 2
    message = capsys.readouterr().err.strip()
    assert message.endswith(
        "temperature columns differ from the modelling run's (missing T3); name the same "
        "inputs in both runs (--temps A,B,C)"
    )
    assert not (tmp_path / "out").exists()


def test_compare_reads_a_validation_run_whose_columns_come_in_another_order(tmp_path):
    plain = pd.read_csv(DATASETS / "validation_speed.csv")
    shuffled = plain[["error_um", "T4", "time_s", "T2", "T_amb", "T1", "speed_rpm", "T6", "T3", "spindle_on", "T5"]]
    rows = []
    for name, frame in (("plain", plain), ("shuffled", shuffled)):
        path, report = tmp_path / f"{name}.csv", tmp_path / f"{name}.json"
        frame.to_csv(path, index=False)
        options = ["--validate", path, "--pmax", "1", "--quiet", "--json", report, "--out", tmp_path / name]
        assert cli("compare", "--data", DATASETS / "paper_cycle.csv", *options) == 0
        rows.append([{**r, "run": None} for r in json.loads(report.read_text())["rows"] if r["run"] == name])
    assert len(rows[0]) >= 3 and rows[0] == rows[1]


@pytest.mark.parametrize("twice", [[200], "all"])
def test_rows_written_twice_are_left_out_with_a_note(tmp_path, capsys, twice):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    rows = list(range(len(log))) if twice == "all" else twice
    doubled = pd.concat([log, log.iloc[rows]]).sort_index(kind="stable")
    path, clean = tmp_path / "twice.csv", tmp_path / "clean.csv"
    doubled.to_csv(path, index=False)
    log.to_csv(clean, index=False)
    twice_left_out, plain = fitted_coefficients(tmp_path, path, clean)
    assert twice_left_out == plain
    first = 202 if twice != "all" else 2
    assert f"{len(rows)} row(s) identical to the row before left out (row {first}" in capsys.readouterr().out


def test_a_reading_that_repeats_under_a_stamp_coarser_than_the_clock_is_kept(tmp_path):
    """A 15 s logger stamping whole minutes at display resolution: rows equal to the one before, stamp and all,
    are readings that did not change, not rows written twice."""
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:240]
    log = log.round({c: 1 for c in log.columns if c.startswith("T")} | {"error_um": 0})
    log["time_s"] = 15.0 * np.arange(len(log))
    minutes = pd.Timestamp("2026-03-02 08:00") + pd.to_timedelta(log["time_s"], unit="s")
    stamped = log.drop(columns="time_s")
    stamped.insert(0, "Date/Time", minutes.dt.strftime("%Y/%m/%d %H:%M"))
    repeated = stamped.eq(stamped.shift()).all(axis=1)
    assert repeated.sum() >= 5
    path, clean = tmp_path / "stamped.csv", tmp_path / "clean.csv"
    stamped.to_csv(path, index=False)
    log.to_csv(clean, index=False)
    kept, plain = fitted_coefficients(tmp_path, path, clean)
    assert np.allclose(kept, plain, rtol=1e-9, atol=1e-9)


def test_a_time_of_day_saved_as_a_fraction_of_a_day_is_named_and_read_in_days(tmp_path, capsys):
    log = pd.read_csv(DATASETS / "paper_cycle.csv")
    fraction = log.assign(time_s=(8 * 3600 + log["time_s"]) / 86400).rename(columns={"time_s": "Uhrzeit"})
    path = tmp_path / "fraction.csv"
    fraction.to_csv(path, index=False, float_format="%.10f")
    assert cli("fit", "--data", path, "--time", "Uhrzeit", *QUICK, "--out", tmp_path / "a") == 0
    assert (
        "if it holds fractions of a day (a spreadsheet's time of day saved as a number), name it so (Uhrzeit [d])"
        in (capsys.readouterr().out)
    )
    named, clean = tmp_path / "named.csv", tmp_path / "clean.csv"
    fraction.rename(columns={"Uhrzeit": "Uhrzeit [d]"}).to_csv(named, index=False, float_format="%.10f")
    log.to_csv(clean, index=False)
    days = fitted_coefficients(tmp_path, named, options=[*QUICK, "--time", "Uhrzeit [d]"])
    assert np.allclose(days, fitted_coefficients(tmp_path, clean), rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("after_row", [3, 49, 300])
def test_a_message_line_in_a_table_split_at_spaces_is_passed_over_wherever_it_falls(tmp_path, capsys, after_row):
    clean = tmp_path / "clean.csv"
    pd.read_csv(DATASETS / "paper_cycle.csv").to_csv(clean, index=False)
    lines = [line.replace(",", "  ") for line in clean.read_text().splitlines()]
    path = tmp_path / "spaced.txt"
    path.write_text("\n".join([*lines[: 1 + after_row], "Logging paused", *lines[1 + after_row :]]) + "\n")
    passed_over, plain = fitted_coefficients(tmp_path, path, clean)
    assert passed_over == plain
    assert f"(row {after_row + 1}: a logger's message, such as 'Logging paused')" in capsys.readouterr().out
