"""The command line of probe checks: replay --probe-every/--probe-column, fit/diagnose --recalibrate,
compare --probe-every, and their bad input."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from recalibration_cases import KALMAN, kalman_model_file, with_section
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main
from groupfit.model import ModelFile
from groupfit.probe_intervals import hold_residual, parse_intervals
from groupfit.runtime import PROBE_APPLIED, PROBE_CODE_OFFSET, SwitchingRule


@pytest.fixture()
def model_path(tmp_path):
    return kalman_model_file(tmp_path)


def replay_json(tmp_path, *args):
    out = tmp_path / "r.json"
    assert main(["replay", *map(str, args), "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_replay_with_checks_reports_them_and_scores_the_corrected_prediction(tmp_path, model_path, capsys):
    plain = replay_json(tmp_path, model_path, "--data", SYNTHETIC)
    checked = replay_json(tmp_path, model_path, "--data", SYNTHETIC, "--probe-every", 1000)  # 10 samples of 100 s
    report = capsys.readouterr().out
    samples = checked["samples"]
    residual = np.array([s["residual_um"] for s in samples])
    error = pd.read_csv(SYNTHETIC)["error_um"].to_numpy()
    assert np.allclose(residual, error - np.array([s["prediction_um"] for s in samples]), atol=1e-12)
    assert checked["rms_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-12)
    probes = checked["probes"]
    checks = [s["i"] for s in samples if "probe" in s]
    assert checks == list(range(10, len(samples) + 1, 10)) == [c["i"] for c in probes["checks"]]
    assert probes["applied"] + probes["rejected"] + probes["ignored"] == len(checks)
    assert probes["rms_without_checks_um"] == pytest.approx(plain["rms_um"], rel=1e-12)
    assert plain["samples"][9]["prediction_um"] == samples[9]["prediction_um"]  # the first check acts afterwards
    assert "probes" in report and "applied" in report and "without" in report


def test_a_check_at_the_start_of_the_run_corrects_from_the_second_sample(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    frame["error_um"] += 5.0  # another day: the whole run 5 µm off what the model knows
    data = tmp_path / "offset.csv"
    frame.to_csv(data, index=False)
    later = replay_json(tmp_path, model_path, "--data", data, "--probe-every", 1000)
    start = replay_json(tmp_path, model_path, "--data", data, "--probe-every", 1000, "--probe-first", 0)
    shifted = replay_json(tmp_path, model_path, "--data", data, "--probe-every", 1000, "--probe-first", 460)
    assert [c["i"] for c in start["probes"]["checks"]] == list(range(1, len(frame) + 1, 10))
    assert [c["i"] for c in shifted["probes"]["checks"]] == list(range(6, len(frame) + 1, 10))  # 460 s: sample 6
    assert start["probes"]["first_s"] == 0 and later["probes"]["first_s"] is None
    first, second = start["samples"][0], start["samples"][1]
    assert first["prediction_um"] == later["samples"][0]["prediction_um"]  # a check acts after its sample
    assert abs(second["residual_um"]) < abs(later["samples"][1]["residual_um"])  # moving at the rate limit
    before = [np.mean([abs(s["residual_um"]) for s in r["samples"][1:9]]) for r in (start, later)]
    assert before[0] < before[1] - 1.0  # taken up before the default first check
    assert start["rms_um"] < later["rms_um"]  # nine samples fewer off by the whole offset


def test_checks_on_a_file_that_continues_a_recording_are_the_whole_recordings_checks_on_its_rows(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    frame.loc[137:, "error_um"] += 3.0  # the rest of the recording moved off the model: the checks correct it
    first, rest = tmp_path / "first.csv", tmp_path / "rest.csv"
    frame.iloc[:137].to_csv(first, index=False)
    frame.iloc[137:].to_csv(rest, index=False)
    continued = replay_json(tmp_path, model_path, "--data", rest, "--continues", first, "--probe-every", 1000)
    plain = replay_json(tmp_path, model_path, "--data", rest, "--continues", first)
    model = ModelFile.load(model_path)
    temps, error = frame[list(model.temps)].to_numpy(float), frame["error_um"].to_numpy(float)
    probes = np.full(len(frame), np.nan)
    rows = np.arange(137 + 9, len(frame), 10)  # every 10 samples of 100 s, counted from the rest's first sample
    probes[rows] = error[rows]
    whole = SwitchingRule(model).replay(temps, probes)
    prediction = np.array([s["prediction_um"] for s in continued["samples"]])
    assert np.array_equal(prediction, whole.prediction_um[137:])
    assert [c["i"] for c in continued["probes"]["checks"]] == list(rows - 137 + 1)
    codes = [int(whole.probe[i]) - PROBE_CODE_OFFSET for i in rows]
    assert continued["probes"]["applied"] == codes.count(PROBE_APPLIED) > 0
    assert continued["probes"]["rms_without_checks_um"] == pytest.approx(plain["rms_um"], rel=1e-12)
    assert continued["rms_um"] < plain["rms_um"]


def test_logged_checks_in_their_own_column(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    frame["probe_um"] = np.nan
    frame.loc[[49, 99, 149], "probe_um"] = frame.loc[[49, 99, 149], "error_um"] + np.array([0.5, 500.0, 0.5])
    data = tmp_path / "logged.csv"
    frame.to_csv(data, index=False)
    result = replay_json(tmp_path, model_path, "--data", data, "--probe-column", "probe_um")
    assert [(c["i"], c["result"]) for c in result["probes"]["checks"]] == [
        (50, "applied"),
        (100, "rejected"),
        (150, "applied"),
    ]


def test_an_infinite_logged_check_is_no_check(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    frame["probe_um"] = np.nan
    frame.loc[[49, 99, 149], "probe_um"] = frame.loc[[49, 99, 149], "error_um"] + np.array([0.5, np.inf, 0.5])
    data = tmp_path / "infinite.csv"
    frame.to_csv(data, index=False)
    result = replay_json(tmp_path, model_path, "--data", data, "--probe-column", "probe_um")
    assert [(c["i"], c["result"]) for c in result["probes"]["checks"]] == [(50, "applied"), (150, "applied")]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--probe-every", "0"], "--probe-every: '0' must be longer than 0"),
        (["--probe-every", "nan"], "--probe-every: 'nan' is not an interval"),
        (["--probe-every", "1000,2000"], "replay takes one interval"),
        (["--probe-column", "nope"], "column 'nope' not found"),
        (["--probe-every", "1000", "--probe-column", "time_s"], "--probe-column 'time_s' is the run's time"),
        (["--probe-column", "T1"], "--probe-column 'T1' is a reading the model takes as an input"),
        (["--probe-every", "1000", "--probe-column", "T9"], "--probe-column 'T9' is named as a temperature sensor"),
        (
            ["--probe-every", "1000", "--probe-first", "-1"],
            "--probe-first -1: must be a number of seconds from 0 to 1e+09",
        ),
        (["--probe-first", "0"], "--probe-first needs --probe-every"),
        (["--probe-every", "1000", "--probe-first", "1e9"], "--probe-first 1e+09: after the run's last sample"),
    ],
)
def test_bad_probe_options_stop_with_one_line(tmp_path, model_path, capsys, args, message):
    assert main(["replay", str(model_path), "--data", str(SYNTHETIC), *args, "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "r.json").exists()


def test_a_model_file_with_a_bad_section_stops_replay_with_one_line(tmp_path, capsys):
    model, _ = synthetic_model()
    data = with_section(model, {**KALMAN, "gate_sigmas": -1.0})
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    assert main(["replay", str(path), "--data", str(SYNTHETIC), "--probe-every", "1000"]) == 2
    err = capsys.readouterr().err.strip()
    assert "recalibration.gate_sigmas" in err and str(path) in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("method", ["auto", "hold", "kalman", "none"])
def test_fit_writes_the_section_it_was_asked_for(tmp_path, method, capsys):
    out = tmp_path / method
    code = main(["fit", "--data", str(SYNTHETIC), "--p", "0", "--out", str(out), "--recalibrate", method, "--quiet"])
    assert code == 0
    recal_lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("recal ")]
    model = ModelFile.load(out / "model.json")
    if method == "none":
        assert model.recalibration is None and not recal_lines
        return
    section = model.recalibration
    assert section.chosen["by"] == "held-out checks" and len(recal_lines) == 1
    assert len(section.chosen["rms_hold_um"]) == len(section.chosen["intervals_s"]) == 4
    if method == "hold":
        assert section.method == "hold"
    if method == "kalman":
        assert section.method == "kalman"
    if method == "auto":  # on the held-out stretches, never worse than the hold beyond what they cannot tell apart
        ratios = np.divide(section.chosen["rms_chosen_um"], section.chosen["rms_hold_um"])
        assert np.mean(np.log(ratios)) <= section.chosen["indifference"] + 1e-12


def test_parse_intervals_and_the_hold_of_compare():
    assert parse_intervals("5m,15m, 1h,90s,120") == [300.0, 900.0, 3600.0, 90.0, 120.0]
    for bad in ("5x", "", "-5m", "0"):
        with pytest.raises(Exception, match="--probe-every"):
            parse_intervals(bad)
    residual = np.array([1.0, 2.0, 4.0, 7.0, 11.0, 16.0, 22.0])
    # checks after samples 3 and 6 (every 3): held from the next sample on
    assert hold_residual(residual, 3).tolist() == [1.0, 2.0, 4.0, 3.0, 7.0, 12.0, 6.0]
    assert hold_residual(residual, 3, 2).tolist() == hold_residual(residual, 3).tolist()  # the default, written out
    # a check after sample 1, then every 3 (after samples 4 and 7): held from the next sample on
    assert hold_residual(residual, 3, 0).tolist() == [1.0, 1.0, 3.0, 6.0, 4.0, 9.0, 15.0]
    assert hold_residual(residual, 3, 10).tolist() == residual.tolist()  # after the run's end: no check


def test_compare_places_its_first_check_as_replay_does(tmp_path, capsys):
    json_path = tmp_path / "c.json"
    args = ["compare", "--pmax", "0", "--probe-every", "30m", "--out", str(tmp_path / "cmp"), "--json", str(json_path)]
    assert main([*args, "--quiet"]) == 0
    later = json.loads(json_path.read_text())["probe_intervals"]
    assert main([*args, "--quiet", "--probe-first", "0"]) == 0
    start = json.loads(json_path.read_text())["probe_intervals"]
    assert "the first 0 s after the run's start" in capsys.readouterr().out
    assert later["first_s"] is None and start["first_s"] == 0
    assert [r["rms_none_um"] for r in start["rows"]] == [r["rms_none_um"] for r in later["rows"]]
    assert [r["rms_um"] for r in start["rows"]] != [r["rms_um"] for r in later["rows"]]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--probe-first", "0"], "--probe-first needs --probe-every"),
        (
            ["--probe-every", "30m", "--probe-first", "-5"],
            "--probe-first -5: must be a number of seconds from 0 to 1e+09",
        ),
    ],
)
def test_compare_refuses_a_bad_first_check_with_one_line(tmp_path, capsys, args, message):
    out = tmp_path / "cmp"
    assert main(["compare", "--pmax", "0", *args, "--out", str(out), "--json", str(tmp_path / "c.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists() and not (tmp_path / "c.json").exists()


def test_compare_prints_and_writes_the_error_against_the_check_interval(tmp_path, capsys):
    out = tmp_path / "cmp"
    code = main(
        ["compare", "--pmax", "1", "--probe-every", "15m,1h", "--out", str(out), "--json", str(tmp_path / "c.json")]
        + ["--quiet"]
    )
    assert code == 0
    report = capsys.readouterr().out
    table = json.loads((tmp_path / "c.json").read_text())["probe_intervals"]
    assert table["intervals_s"] == [900.0, 3600.0] and table["method"] == "offset hold"
    assert {row["model"] for row in table["rows"]} == {"mlr", "fit", "ar1", "grouped1"}  # fit's: p = 0, a stage
    assert "RMS µm with a probe check every T" in report
    assert (out / "error_against_check_interval.png").stat().st_size > 10_000


def test_a_log_measured_on_some_rows_is_checked_where_it_was_measured(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    sparse = frame.assign(error_um=np.where(np.arange(len(frame)) % 4 == 1, frame["error_um"], np.nan))
    path = tmp_path / "sparse.csv"
    sparse.to_csv(path, index=False)
    checked = replay_json(tmp_path, model_path, "--data", path, "--probe-every", 1000)  # due after rows 10, 20 …
    due = np.arange(9, len(frame), 10)
    measured = np.flatnonzero(np.isfinite(sparse["error_um"].to_numpy()))
    expected = [int(measured[measured >= r][0]) for r in due if (measured >= r).any()]
    expected = [m for m, r in zip(expected, due) if m < r + 10]  # a reading before the next check is due
    assert [c["i"] - 1 for c in checked["probes"]["checks"]] == expected
    assert [c["reading_um"] for c in checked["probes"]["checks"]] == [float(sparse["error_um"][m]) for m in expected]
