"""Logs as loggers write them: a jittering clock, several readings per cycle, a gap, a file that continues.

Every log here is made up to imitate one of a printer's or a spindle's: cycle
means stamped to the second with cycles 59.3–60.4 s apart; three readings 4 s
apart once a minute (a 4 s / 4 s / 52 s rhythm); the same with a gap of ten
minutes; one recording split into two files, the second with its clock going
on or starting again.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run, load_runs
from groupfit.errors import InputError
from groupfit.resample import GAP_PERIODS, resample_frame

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
N = 360


def cycle_means(seed: int = 1, n: int = N, *, shift: int = 0) -> pd.DataFrame:
    """A printer's frame drift as cycle means on the logger's clock: cycles 59.3–60.4 s, stamps to 1 s."""
    rng = np.random.default_rng(seed)
    time = np.round(np.concatenate([[0.0], np.cumsum(rng.uniform(59.3, 60.4, n - 1))]))
    k = np.arange(n) + shift
    bed_target = np.where((k % 180) < 100, 60.0, 0.0)
    heat = np.convolve(bed_target / 60.0, np.exp(-np.arange(120) / 25.0), "full")[:n]
    slow = np.convolve(bed_target / 60.0, np.exp(-np.arange(240) / 70.0), "full")[:n]
    t1 = 22.0 + 0.12 * heat + rng.normal(0, 0.02, n)
    t2 = 22.0 + 0.05 * slow + rng.normal(0, 0.02, n)
    error = 4.0 * (t1 - 22.0) + 6.0 * (t2 - 22.0) + 0.3 * np.sin(k / 15.0) + rng.normal(0, 0.1, n)
    return pd.DataFrame({"time_s": time, "T1": t1, "T2": t2, "bed_target": bed_target, "error_um": error})


def three_per_cycle(means: pd.DataFrame, seed: int = 2) -> pd.DataFrame:
    """Three readings 4 s apart once a minute (a 4 s / 4 s / 52 s rhythm), each with its own noise."""
    rng = np.random.default_rng(seed)
    rows = []
    for k, row in enumerate(means.itertuples(index=False)):
        for j in range(3):
            reading = row._asdict()
            reading["time_s"] = 60.0 * k + 4.0 * j + 7.0
            for column in ("T1", "T2", "error_um"):
                reading[column] += rng.normal(0, 0.05)
            rows.append(reading)
    return pd.DataFrame(rows)


def cli(*args) -> int:
    return main([str(a) for a in args])


# ------------------------------------------------------------------------- a jittering clock


def test_a_jittering_clock_within_the_tolerance_is_accepted_with_its_largest_deviation(tmp_path):
    frame = cycle_means()
    run = load_run(frame, temps=["T1", "T2"], name="printer")
    steps = np.diff(frame["time_s"].to_numpy())
    worst = np.max(np.abs(steps - np.median(steps)))  # brute force
    assert run.period == 60.0 and steps.min() < 60.0 < steps.max()
    assert len(run.notes) == 1 and f"largest deviation {worst:.4g} s" in run.notes[0]
    assert f"({100 * worst / 60.0:.2f} %" in run.notes[0]


def test_an_interval_beyond_the_tolerance_is_refused_unless_widened(tmp_path):
    frame = cycle_means()
    frame.loc[100:, "time_s"] += 2.0  # one interval of 62 s: 3.3 % off
    with pytest.raises(InputError, match=r"rows 100 to 101 .*tolerance 2 %.*--resample SECONDS.*--period-tolerance"):
        load_run(frame, temps=["T1", "T2"])
    assert load_run(frame, temps=["T1", "T2"], period_tolerance=0.05).period == 60.0
    path = tmp_path / "late.csv"
    frame.to_csv(path, index=False)
    assert cli("fit", "--data", path, "--p", "0", "--out", tmp_path / "a") == 2
    assert cli("fit", "--data", path, "--p", "0", "--period-tolerance", "5", "--out", tmp_path / "b") == 0


def test_cycle_means_on_their_real_clock_fit_without_flags(tmp_path, capsys):
    path = tmp_path / "printer_a.csv"
    cycle_means().to_csv(path, index=False)
    assert cli("fit", "--data", path, "--p", "2", "--json", tmp_path / "m.json", "--out", tmp_path) == 0
    assert "time stamps jitter around the period of 60 s" in capsys.readouterr().out
    assert json.loads((tmp_path / "m.json").read_text())["sampling_period_s"] == 60.0


def rounded_clock(period_s: float, n: int = N) -> pd.DataFrame:
    """:func:`cycle_means` sampled every ``period_s`` exactly, its stamps written to whole seconds."""
    frame = cycle_means(n=n)
    frame["time_s"] = np.round(np.arange(n) * period_s)
    return frame


@pytest.mark.parametrize("period_s", [10.4, 15.3, 29.6])
def test_stamps_rounded_to_the_second_are_read_on_their_mean_step_and_fit_as_the_exact_clock(tmp_path, period_s):
    rounded, exact = rounded_clock(period_s), cycle_means()
    exact["time_s"] = np.arange(N) * period_s
    steps = np.diff(rounded["time_s"].to_numpy())
    beyond_tolerance = np.max(np.abs(steps - np.median(steps))) / np.median(steps) > 0.02
    assert steps.max() - steps.min() == 1.0 and beyond_tolerance
    run = load_run(rounded, temps=["T1", "T2"])
    assert run.period == pytest.approx((rounded["time_s"].iloc[-1] - rounded["time_s"].iloc[0]) / (N - 1), rel=1e-12)
    assert run.period == pytest.approx(period_s, abs=0.5 / (N - 1))
    stamped = rounded.assign(time_s=None).rename(columns={"time_s": "Timestamp"})
    stamped["Timestamp"] = (pd.Timestamp("2026-03-02 23:00:00") + pd.to_timedelta(rounded["time_s"], unit="s")).astype(
        str
    )
    coefficients = []
    for name, frame in (("rounded", rounded), ("text", stamped), ("exact", exact)):
        path, report = tmp_path / f"{name}.csv", tmp_path / f"{name}.json"
        frame.to_csv(path, index=False)
        options = ["--p", "0", "--ridge", "0", "--recalibrate", "none", "--quiet", "--json", report]
        assert cli("fit", "--data", path, "--temps", "T1,T2", *options, "--out", tmp_path / name) == 0
        coefficients.append(json.loads(report.read_text())["coefficients"])
    assert coefficients[0] == coefficients[1] == coefficients[2]


def test_a_missed_sample_between_rounded_stamps_is_still_refused():
    frame = rounded_clock(10.4).drop(index=150)
    with pytest.raises(InputError, match=r"rows 150 to 151 of column 'time_s' are 2\d s apart but the period is 10 s"):
        load_run(frame, temps=["T1", "T2"])
    every_second = rounded_clock(1.0).drop(index=150)  # a resolution as coarse as the period tells nothing
    with pytest.raises(InputError, match=r"rows 150 to 151 of column 'time_s' are 2 s apart"):
        load_run(every_second, temps=["T1", "T2"])


# ------------------------------------------------------------------------- several readings per period


def test_three_readings_per_cycle_are_averaged_into_their_minute():
    means = cycle_means()
    raw = three_per_cycle(means)
    binned = resample_frame(raw, time="time_s", period_s=60.0, label="raw")
    (piece,) = binned.pieces
    assert binned.combined == 3 * N and binned.empty == 0 and not binned.gaps
    by_cycle = raw.groupby(np.arange(len(raw)) // 3)[["T1", "T2", "error_um"]].mean()  # brute force
    np.testing.assert_allclose(piece[["T1", "T2", "error_um"]].to_numpy(), by_cycle.to_numpy(), rtol=0, atol=1e-12)
    # each bin's centre is its time: the middle of its three readings (4 s after the first), 60 s apart
    np.testing.assert_allclose(piece["time_s"].to_numpy(), 60.0 * np.arange(N) + 11.0, atol=1e-9)


def test_the_raw_log_is_read_as_bursts_as_it_is_and_as_resample_reads_it(tmp_path, capsys):
    path = tmp_path / "printer_raw.csv"
    three_per_cycle(cycle_means()).to_csv(path, index=False)
    reports = []
    for name, extra in (("plain", ()), ("resampled", ("--resample", "60"))):
        report = tmp_path / f"{name}.json"
        assert cli("fit", "--data", path, "--p", "2", *extra, "--json", report, "--out", tmp_path / name) == 0
        reports.append(json.loads(report.read_text()))
        out = capsys.readouterr().out
        assert f"{3 * N} reading(s) averaged into {N} period(s), 0 empty" in out
        assert ("bursts of 3 every 60 s" in out) == (name == "plain")
    assert reports[0]["coefficients"] == reports[1]["coefficients"] and reports[0]["breaks"] == reports[1]["breaks"]
    config = tmp_path / "printer.toml"
    config.write_text(f'[data]\npath = "{path.name}"\ntemps = ["T1", "T2"]\nresample_s = 60\n[model]\np = 2\n')
    assert cli("fit", config, "--out", tmp_path / "c") == 0


def test_a_missed_cycle_is_interpolated_and_a_gap_splits_the_log(tmp_path, capsys):
    raw = three_per_cycle(cycle_means())
    cycle = np.arange(len(raw)) // 3
    one_missed = raw[cycle != 50]
    binned = resample_frame(one_missed, time="time_s", period_s=60.0, label="raw")
    (piece,) = binned.pieces
    assert binned.empty == 1 and len(piece) == N
    expected = (piece["T1"].iloc[49] + piece["T1"].iloc[51]) / 2  # midway: linear in time
    assert piece["T1"].iloc[50] == pytest.approx(expected, abs=1e-12)
    gap = raw[(cycle < 150) | (cycle >= 160)]  # ten minutes without a reading
    runs = load_runs(gap, temps=["T1", "T2"], resample=60.0, name="gap")
    assert [r.n_samples for r in runs] == [150, N - 160] and 10 > GAP_PERIODS
    assert runs[1].time[0] - runs[0].time[-1] == pytest.approx(11 * 60.0)  # not bridged
    assert "split into 2 runs at 1 gap(s)" in runs[0].notes[0]
    path = tmp_path / "gap.csv"
    gap.to_csv(path, index=False)
    assert cli("fit", "--data", path, "--p", "2", "--resample", "60", "--out", tmp_path) == 2
    assert "--resample split the log at its gaps" in capsys.readouterr().err
    assert cli("fit", "--data", path, "--p", "0", "--resample", "60", "--out", tmp_path) == 0
    assert cli("compare", "--data", path, "--resample", "60", "--out", tmp_path / "c") == 2  # grouped: one run
    assert "splits the log into 2 runs at gaps" in capsys.readouterr().err
    # the pieces of one log are one recording to the next-run estimate, not two days to leave out in turn
    report = tmp_path / "gap.json"
    assert cli("fit", "--data", path, "--resample", "60", "--json", report, "--out", tmp_path / "auto") == 0
    assert "leave-one-run-out" not in json.loads(report.read_text())["expected_next_run_method"]


def test_a_sensor_missing_a_few_readings_is_interpolated_and_a_longer_silence_refused(tmp_path, capsys):
    means = cycle_means().assign(time_s=60.0 * np.arange(N))  # a steady clock: one reading a period
    holes = means.copy()
    holes.loc[40:42, "T1"] = np.nan  # three readings missed in a row: filled
    holes.loc[90, "T2"] = np.nan
    holes.loc[0, "T2"] = np.nan  # before any reading of T2: nothing to fill it from, the period is dropped
    binned = resample_frame(holes, time="time_s", period_s=60.0, label="holes", measured=("error_um",))
    (piece,) = binned.pieces
    assert binned.missed == 4 and binned.empty == 0 and binned.trimmed == 1
    note = binned.note("holes", 60.0, len(piece))
    assert "4 missed reading(s) of a column interpolated, 1 period(s) at the ends without a reading" in note
    assert len(piece) == N - 1 and piece["T2"].notna().all()
    t = piece["time_s"].to_numpy()
    for column, rows in (("T1", [39, 40, 41]), ("T2", [89])):
        known = [rows[0] - 1, rows[-1] + 1]
        truth = np.interp(t[rows], t[known], piece[column].to_numpy()[known])  # a line between the neighbours
        np.testing.assert_allclose(piece[column].to_numpy()[rows], truth, rtol=0, atol=1e-12)
    path = tmp_path / "holes.csv"
    holes.iloc[1:].to_csv(path, index=False)
    assert cli("fit", "--data", path, "--temps", "T1,T2", "--p", "0", "--out", tmp_path) == 2
    assert "or let --resample SECONDS interpolate up to 3 missed readings" in capsys.readouterr().err
    assert cli("fit", "--data", path, "--temps", "T1,T2", "--p", "0", "--resample", "60", "--out", tmp_path) == 0
    silent = means.copy()
    silent.loc[40 : 40 + GAP_PERIODS, "T1"] = np.nan  # one reading more than is filled
    runs = load_runs(silent, temps=["T1", "T2"], resample=60.0, name="silent", allow_nonfinite=True)
    assert np.isnan(runs[0].temps[40 : 41 + GAP_PERIODS, 0]).all()
    with pytest.raises(InputError, match="row 41, column 'T1' is empty"):
        load_runs(silent, temps=["T1", "T2"], resample=60.0, name="silent")


def test_a_missing_error_is_never_made_up(tmp_path):
    probed = cycle_means().assign(time_s=60.0 * np.arange(N))
    probed.loc[probed.index % 3 != 0, "error_um"] = np.nan  # a probe cycle every third sample
    (run,) = load_runs(probed, temps=["T1", "T2"], resample=60.0, name="probed", missing_error=True)
    np.testing.assert_array_equal(np.isfinite(run.error), probed.index % 3 == 0)


# ------------------------------------------------------------------------- a file that continues


@pytest.fixture(scope="module")
def split_recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("spindle")
    whole = cycle_means(seed=5, n=600)
    whole.to_csv(folder / "whole.csv", index=False)
    whole.iloc[:330].to_csv(folder / "first.csv", index=False)
    whole.iloc[330:].to_csv(folder / "rest.csv", index=False)
    restarted = whole.iloc[330:].copy()
    restarted["time_s"] -= restarted["time_s"].iloc[0]
    restarted.to_csv(folder / "rest_restarted.csv", index=False)
    assert cli("fit", "--data", folder / "first.csv", "--p", "3", "--out", folder, "--quiet") == 0
    return folder


def replayed(folder, *args) -> dict:
    out = folder / "replay.json"
    assert cli("replay", folder / "model.json", *args, "--json", out) == 0
    return json.loads(out.read_text())


@pytest.mark.parametrize("rest", ["rest.csv", "rest_restarted.csv"])
def test_replay_continues_equals_the_whole_recording_on_the_continued_part(split_recording, rest):
    folder = split_recording
    whole = replayed(folder, "--data", folder / "whole.csv")["samples"][330:]
    alone = replayed(folder, "--data", folder / rest, "--fresh")
    continued = replayed(folder, "--data", folder / rest, "--continues", folder / "first.csv")
    assert continued["history_samples"] == 330 and len(continued["samples"]) == len(whole)
    prediction = np.array([s["prediction_um"] for s in continued["samples"]])
    assert np.max(np.abs(prediction - [s["prediction_um"] for s in whole])) <= 1e-9
    assert [s["group"] for s in continued["samples"]] == [s["group"] for s in whole]
    assert alone["samples"][0]["group"] == 1 and whole[0]["group"] > 1  # restarted, the rule starts again


def test_the_rest_whose_clock_continues_the_modelling_file_is_replayed_after_it_unasked(split_recording, capsys):
    folder = split_recording
    model = json.loads((folder / "model.json").read_text())
    (recording,) = model["training"]["recordings"]
    last = pd.read_csv(folder / "first.csv")["time_s"].iloc[-1]
    assert recording["path"] == str((folder / "first.csv").resolve()) and recording["last_time_s"] == last
    unasked = replayed(folder, "--data", folder / "rest.csv")
    assert "continues the modelling recording" in capsys.readouterr().out
    declared = replayed(folder, "--data", folder / "rest.csv", "--continues", folder / "first.csv")
    assert unasked["samples"] == declared["samples"] and unasked["history_samples"] == 330
    assert unasked["continues"] == [recording["path"]]
    fresh = replayed(folder, "--data", folder / "rest.csv", "--fresh")
    assert fresh["continues"] == [] and fresh["samples"][0]["group"] == 1 < unasked["samples"][0]["group"]


def test_the_rest_whose_clock_starts_again_is_told_by_its_first_row_and_replayed_after_the_modelling_file(
    split_recording, capsys
):
    folder = split_recording
    capsys.readouterr()
    restarted = replayed(folder, "--data", folder / "rest_restarted.csv")
    assert "its first row picks up where the modelling recording" in capsys.readouterr().out
    declared = replayed(folder, "--data", folder / "rest.csv", "--continues", folder / "first.csv")
    assert restarted["history_samples"] == 330 and restarted["continues"] == declared["continues"]
    own_clock = [{**sample, "time_s": None} for sample in restarted["samples"]]  # each file's own time stamps
    assert own_clock == [{**sample, "time_s": None} for sample in declared["samples"]]
    fresh = replayed(folder, "--data", folder / "rest_restarted.csv", "--fresh")
    assert fresh["continues"] == [] and fresh["samples"][0]["group"] == 1 < restarted["samples"][0]["group"]


def test_a_folder_moved_whole_keeps_the_model_and_its_modelling_file_together(split_recording, tmp_path):
    moved = tmp_path / "elsewhere"
    moved.mkdir()
    for name in ("model.json", "first.csv", "rest.csv"):
        (moved / name).write_bytes((split_recording / name).read_bytes())
    model = json.loads((moved / "model.json").read_text())
    (recording,) = model["training"]["recordings"]
    assert recording["path_from_model"] == "first.csv"
    recording["path"] = str(tmp_path / "gone" / "first.csv")  # the absolute path no longer leads to it
    (moved / "model.json").write_text(json.dumps(model))
    result = replayed(moved, "--data", moved / "rest.csv")
    assert result["continues"] == [str(moved / "first.csv")] and result["history_samples"] == 330


@pytest.mark.parametrize("change", ["edited", "moved", "other columns"])
@pytest.mark.parametrize("state_kept", [True, False], ids=["state kept", "older file"])
def test_a_modelling_file_changed_or_gone_since_the_fit_is_not_continued_and_the_note_says_why(
    split_recording, tmp_path, capsys, change, state_kept
):
    for name in ("model.json", "first.csv", "rest.csv"):
        (tmp_path / name).write_bytes((split_recording / name).read_bytes())
    model = json.loads((tmp_path / "model.json").read_text())
    model["training"]["recordings"][0]["path"] = str(tmp_path / "first.csv")
    if not state_kept:
        del model["training"]["recordings"][0]["end_state"]
    (tmp_path / "model.json").write_text(json.dumps(model))
    if change == "edited":
        (tmp_path / "first.csv").write_text((tmp_path / "first.csv").read_text().replace(",", ", ", 1))
    elif change == "moved":
        (tmp_path / "first.csv").unlink()
    else:  # the rest logged with one more column: not the same recording, whatever its clock
        rest = pd.read_csv(tmp_path / "rest.csv").assign(spare=0.0)
        rest.to_csv(tmp_path / "rest.csv", index=False)
    result = replayed(tmp_path, "--data", tmp_path / "rest.csv")
    said = capsys.readouterr().out
    expected = {
        "edited": "has changed",
        "moved": "no longer there",
        "other columns": "its columns differ (it adds spare",
    }
    assert expected[change] in said
    if state_kept and change != "other columns":  # the rule's state at the file's end stands in for it
        declared = replayed(split_recording, "--data", split_recording / "rest.csv")
        assert result["samples"] == declared["samples"] and result["history_samples"] == 330
        assert "replayed from the rule's state at that file's end" in said
    else:
        assert result["continues"] == [] and result["samples"][0]["group"] == 1


def test_fresh_and_continues_together_are_refused(split_recording, capsys):
    folder = split_recording
    args = ("replay", folder / "model.json", "--data", folder / "rest.csv", "--fresh", "--continues", folder / "x")
    assert cli(*args) == 2
    assert "--fresh and --continues" in capsys.readouterr().err


def test_compare_detects_a_continuing_clock_or_first_row_and_takes_continues_for_a_restarted_one(
    split_recording, tmp_path, capsys
):
    folder = split_recording
    later = pd.read_csv(folder / "rest_restarted.csv")
    later.iloc[60:].to_csv(tmp_path / "rest_later.csv", index=False)  # its clock starts again, half an hour on
    results = {}
    cases = (("rest.csv", ()), ("rest_restarted.csv", ("--continues",)), ("rest_restarted.csv", ()))
    for rest, extra in (*cases, (tmp_path / "rest_later.csv", ()), (tmp_path / "rest_later.csv", ("--continues",))):
        out = folder / "compare.json"
        args = ("--data", folder / "first.csv", "--validate", folder / rest, "--pmax", "1", "--heat", "bed_target")
        assert cli("compare", *args, *extra, "--quiet", "--json", out, "--out", folder / "c") == 0
        rows = json.loads(out.read_text())["rows"]
        results[(rest, extra)] = next(
            r for r in rows if r["model"] == "grouped" and r["p"] == 1 and r["run"] != "first"
        )
        report = capsys.readouterr().out
        assert ("continue" in report) == (rest != tmp_path / "rest_later.csv" or bool(extra))
    assert results[("rest.csv", ())]["rms_um"] == pytest.approx(
        results[("rest_restarted.csv", ("--continues",))]["rms_um"]
    )
    assert results[("rest.csv", ())]["rms_um"] == pytest.approx(results[("rest_restarted.csv", ())]["rms_um"])
    later = (tmp_path / "rest_later.csv", ())
    assert results[later]["rms_um"] != results[(tmp_path / "rest_later.csv", ("--continues",))]["rms_um"]


# ------------------------------------------------------------------------- compare's heat column


def test_compare_takes_the_heat_column_by_flag_or_leaves_the_ar1_out(tmp_path, capsys):
    path = tmp_path / "printer.csv"
    cycle_means().to_csv(path, index=False)
    assert cli("compare", "--data", path, "--pmax", "1", "--heat", "speed_rpm", "--quiet", "--out", tmp_path) == 2
    err = capsys.readouterr().err
    assert "heat column 'speed_rpm'" in err and "--heat COLUMN" in err and "--heat none" in err
    default = tmp_path / "default.json"  # the default heat level absent: the run's only operating column, noted
    assert cli("compare", "--data", path, "--pmax", "1", "--quiet", "--json", default, "--out", tmp_path) == 0
    assert json.loads(default.read_text())["ar1"]["heat"] == "bed_target"
    assert "AR(1): heat level 'bed_target', the run's only operating column" in capsys.readouterr().out
    out = tmp_path / "c.json"
    assert (
        cli(
            "compare",
            "--data",
            path,
            "--pmax",
            "1",
            "--heat",
            "bed_target",
            "--quiet",
            "--json",
            out,
            "--out",
            tmp_path,
        )
        == 0
    )
    result = json.loads(out.read_text())
    assert result["ar1"]["heat"] == "bed_target" and any(r["model"] == "ar1" for r in result["rows"])
    assert (
        cli("compare", "--data", path, "--pmax", "1", "--heat", "none", "--quiet", "--json", out, "--out", tmp_path)
        == 0
    )
    result = json.loads(out.read_text())
    assert result["ar1"] is None and not any(r["model"] == "ar1" for r in result["rows"])
    assert "AR(1): left out" in capsys.readouterr().out


def compare_json(tmp_path, name: str, frame: pd.DataFrame, *args) -> dict:
    path = tmp_path / f"{name}.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / f"{name}.json"
    assert cli("compare", "--data", path, "--pmax", "1", "--quiet", "--json", out, "--out", tmp_path / name, *args) == 0
    return json.loads(out.read_text())


def ar1_rows(result: dict) -> list[tuple]:
    return [(r["run"], r["rms_um"], r["max_um"]) for r in result["rows"] if r["model"] == "ar1"]


def test_a_speed_column_of_another_name_is_the_ar1_heat_level_and_the_condition_as_speed_rpm_is(tmp_path, capsys):
    shipped = pd.read_csv(DATASETS / "paper_cycle.csv")
    reference = compare_json(tmp_path, "shipped", shipped)
    renamed = compare_json(tmp_path, "renamed", shipped.rename(columns={"speed_rpm": "Spindle speed [1/min]"}))
    assert "AR(1): heat level 'Spindle speed [1/min]', the run's operating column named as a speed" in (
        capsys.readouterr().out
    )
    assert renamed["ar1"]["heat"] == "Spindle speed [1/min]"
    expected = [value for _, *values in ar1_rows(reference) for value in values]
    assert [value for _, *values in ar1_rows(renamed) for value in values] == pytest.approx(expected, abs=1e-12)
    assert renamed["condition_changes"] == reference["condition_changes"] != []


def test_operating_columns_none_named_as_a_speed_leave_the_ar1_out_and_are_named(tmp_path, capsys):
    shipped = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame = shipped.rename(columns={"speed_rpm": "programme"})
    frame["coolant"] = np.where(np.arange(len(frame)) < len(frame) // 3, 1.0, 2.0)
    result = compare_json(tmp_path, "two", frame)
    assert result["ar1"] is None and not ar1_rows(result)
    out = capsys.readouterr().out
    assert "of its operating columns (programme, spindle_on, coolant) none is named as a speed" in out
    named = compare_json(tmp_path, "named", frame, "--heat", "programme")
    assert named["ar1"]["heat"] == "programme"


def test_a_heat_column_of_text_is_named_with_its_cell_not_a_traceback(tmp_path, capsys):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame["speed_rpm"] = frame["speed_rpm"].astype(object)
    frame.loc[5, "speed_rpm"] = "high"  # a word where the speed should be
    path = tmp_path / "text_speed.csv"
    frame.to_csv(path, index=False)
    assert cli("compare", "--data", path, "--pmax", "1", "--quiet", "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "column 'speed_rpm': 'high' is not a number" in err[0]
