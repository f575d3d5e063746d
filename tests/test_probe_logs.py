"""Logged probe readings as users log them: resampled, continuing the modelling recording, in mm or from a
gauge's own zero, beyond the routine's limit; and the options and files around them (huge numbers in a model
file, an AR(1) or position fit asked for a recalibration, a diagnose that would write over its model)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from recalibration_cases import KALMAN, kalman_model_file, with_section
from test_recalibration_cli import replay_json
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main
from groupfit.model import ModelFile
from groupfit.model_recalibration import RECALIBRATION_LIMIT
from groupfit.runtime.recalibration import PROBE_LIMIT_UM

DATASETS = SYNTHETIC.parent


@pytest.fixture()
def model_path(tmp_path):
    return kalman_model_file(tmp_path)


def with_probe(rows, *, drop=()) -> pd.DataFrame:
    frame = pd.read_csv(SYNTHETIC)
    frame["probe_um"] = np.nan
    frame.loc[rows, "probe_um"] = frame.loc[rows, "error_um"]
    return frame.drop(index=list(drop)).reset_index(drop=True)


def test_resampling_makes_up_no_probe_reading_next_to_a_missed_cycle(tmp_path, model_path):
    rows = list(range(9, 300, 10))
    frame = with_probe(rows, drop=(10, 11))  # the logger missed the two cycles after a check
    frame.to_csv(tmp_path / "run.csv", index=False)
    result = replay_json(
        tmp_path, model_path, "--data", tmp_path / "run.csv", "--resample", 100, "--probe-column", "probe_um"
    )
    checks = result["probes"]["checks"]
    assert len(checks) == len(rows)  # not one more between the checks 1000 s apart
    logged = frame["probe_um"].dropna().to_numpy()
    assert np.array_equal([c["reading_um"] for c in checks], logged)


def test_a_sparse_probe_column_trims_no_row_when_resampled(tmp_path, model_path):
    frame = with_probe(list(range(2, 298, 10)))  # its first reading on the third row, its last before the end
    frame.to_csv(tmp_path / "run.csv", index=False)
    result = replay_json(
        tmp_path, model_path, "--data", tmp_path / "run.csv", "--resample", 100, "--probe-column", "probe_um"
    )
    assert result["n_samples"] == len(frame)
    assert result["samples"][0]["time_s"] == frame["time_s"].iloc[0]


def test_a_continuation_that_logs_probe_readings_is_replayed_as_the_rest(tmp_path):
    frame = pd.read_csv(SYNTHETIC)
    first, rest = frame.iloc[:200], frame.iloc[200:].copy()
    first.to_csv(tmp_path / "first.csv", index=False)
    rest.to_csv(tmp_path / "rest.csv", index=False)
    rest["probe_um"] = np.where(np.arange(len(rest)) % 10 == 9, rest["error_um"], np.nan)
    rest.to_csv(tmp_path / "rest_probe.csv", index=False)
    fit = ["fit", "--data", str(tmp_path / "first.csv"), "--p", "2", "--out", str(tmp_path / "m"), "--quiet"]
    assert main([*fit, "--recalibrate", "none"]) == 0
    model = tmp_path / "m" / "model.json"
    plain = replay_json(tmp_path, model, "--data", tmp_path / "rest.csv")
    probe = ("--data", tmp_path / "rest_probe.csv", "--probe-column", "probe_um")
    logged = replay_json(tmp_path, model, *probe)
    assert plain["continues"] and logged["continues"]
    assert [s["group"] for s in logged["samples"]] == [s["group"] for s in plain["samples"]]
    told = replay_json(tmp_path, model, *probe, "--continues", tmp_path / "first.csv")
    assert [s["group"] for s in told["samples"]] == [s["group"] for s in plain["samples"]]
    assert len(told["probes"]["checks"]) == len(logged["probes"]["checks"]) == rest["probe_um"].notna().sum()


def test_a_probe_column_in_mm_is_read_once_in_um(tmp_path, model_path, capsys):
    frame = with_probe(list(range(9, 300, 10)))
    frame["probe_mm"] = frame.pop("probe_um") / 1000.0
    frame.to_csv(tmp_path / "run.csv", index=False)
    by_name = replay_json(tmp_path, model_path, "--data", tmp_path / "run.csv", "--probe-column", "probe_mm")
    assert [c["reading_um"] for c in by_name["probes"]["checks"]] == pytest.approx(
        frame["probe_mm"].dropna().to_numpy() * 1000.0, rel=1e-12
    )
    args = ["replay", str(model_path), "--data", str(tmp_path / "run.csv"), "--probe-column", "probe_mm*1000"]
    assert main([*args, "--json", str(tmp_path / "twice.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert "in mm by its name" in err and "give --probe-column 'probe_mm'" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "twice.json").exists()


def test_a_gauge_read_from_its_start_is_taken_less_its_first_reading(tmp_path, model_path):
    frame = pd.read_csv(SYNTHETIC)
    gauge = frame["error_um"].to_numpy() + 40.0  # a stand-off of 40 µm in every reading
    frame["gauge_um"] = gauge
    frame["sparse_um"] = np.where(np.arange(len(frame)) % 10 == 9, gauge, np.nan)  # logged at the checks alone
    frame.to_csv(tmp_path / "run.csv", index=False)
    for column, start in (("gauge_um", gauge[0]), ("sparse_um", gauge[9])):
        args = ("--data", tmp_path / "run.csv", "--probe-every", 1000, "--probe-column", f"{column}-start")
        result = replay_json(tmp_path, model_path, *args)
        checks = result["probes"]["checks"]
        rows = np.array([c["i"] for c in checks]) - 1
        assert [c["reading_um"] for c in checks] == pytest.approx(gauge[rows] - start, abs=1e-12)


def test_readings_beyond_the_probe_limit_are_named_in_the_report(tmp_path, model_path, capsys):
    frame = with_probe([99, 199])
    frame.loc[99, "probe_um"] = 2.0 * PROBE_LIMIT_UM
    frame.to_csv(tmp_path / "run.csv", index=False)
    result = replay_json(tmp_path, model_path, "--data", tmp_path / "run.csv", "--probe-column", "probe_um")
    assert [c["result"] for c in result["probes"]["checks"]] == ["ignored", "applied"]
    report = capsys.readouterr().out
    assert f"1 of them read beyond ±{PROBE_LIMIT_UM:g} µm" in report


def test_an_interval_takes_the_units_compare_takes(tmp_path, model_path):
    seconds = replay_json(tmp_path, model_path, "--data", SYNTHETIC, "--probe-every", 600)
    minutes = replay_json(tmp_path, model_path, "--data", SYNTHETIC, "--probe-every", "10m")
    assert minutes["probes"]["checks"] == seconds["probes"]["checks"]
    assert minutes["rms_um"] == seconds["rms_um"]


@pytest.mark.parametrize("key", ["sampling_period_s", "coefficients", "recalibration"])
def test_an_integer_too_long_for_a_float_in_a_model_file_is_refused_by_its_key(tmp_path, capsys, key):
    model, _ = synthetic_model()
    text = json.dumps(with_section(model, KALMAN))
    huge = "1" + "0" * 400
    if key == "recalibration":
        text = text.replace('"gate_sigmas": 4.0', f'"gate_sigmas": {huge}')
    elif key == "coefficients":
        data = json.loads(text)
        data["coefficients"][0][0] = 12345.0
        text = json.dumps(data).replace("12345.0", huge)
    else:
        data = json.loads(text)
        data["sampling_period_s"] = 12345.0
        text = json.dumps(data).replace("12345.0", huge)
    assert huge in text
    path = tmp_path / "huge.json"
    path.write_text(text)
    assert main(["replay", str(path), "--data", str(SYNTHETIC)]) == 2
    err = capsys.readouterr().err.strip()
    assert str(path) in err and len(err.splitlines()) == 1 and "Traceback" not in err


def test_an_integer_too_long_for_a_float_in_a_json_log_is_named(tmp_path, capsys):
    frame = pd.read_csv(SYNTHETIC).iloc[:60]
    text = frame.to_json(orient="records")
    text = text.replace(f'"T1":{frame["T1"].iloc[10]}', '"T1":1' + "0" * 400, 1)
    path = tmp_path / "log.json"
    path.write_text(text)
    assert main(["fit", "--data", str(path), "--p", "0", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "row 11, column 'T1'" in err and len(err.splitlines()) == 1


def test_errors_the_range_allows_get_a_recalibration_within_the_model_files_bounds(tmp_path):
    frame = pd.read_csv(SYNTHETIC)
    frame["error_um"] = frame["error_um"] * 1.0e5  # up to ~1e6 µm, allowed by --range-error
    assert frame["error_um"].abs().max() > RECALIBRATION_LIMIT / 2
    frame.to_csv(tmp_path / "big.csv", index=False)
    out = tmp_path / "m"
    args = ["fit", "--data", str(tmp_path / "big.csv"), "--p", "0", "--range-error", "1e8", "--out", str(out)]
    assert main([*args, "--quiet"]) == 0
    section = json.loads((out / "model.json").read_text())["recalibration"]
    assert section["offset_max_um"] <= RECALIBRATION_LIMIT and section["rate_um_per_sample"] <= RECALIBRATION_LIMIT


def test_the_text_sheet_gives_the_output_range_the_checks_may_reach_in_counts(tmp_path, model_path):
    assert main(["export", str(model_path), "--target", "sheet", "--out", str(tmp_path / "s")]) == 0
    integer = json.loads((tmp_path / "s" / "groupfit_sheet.json").read_text())["integer"]
    assert integer["output_counts"] != integer["clamp_counts"]
    text = (tmp_path / "s" / "groupfit_sheet.txt").read_text()
    low, high = integer["output_counts"]
    assert f"output in counts (probe checks may carry it past the clamp): [{low}, {high}]" in text


def test_a_recalibration_asked_of_a_model_that_takes_none_is_refused(tmp_path, capsys):
    ar1 = ["fit", "--model", "ar1", "--data", str(DATASETS / "paper_cycle.csv"), "--heat", "speed_rpm"]
    assert main([*ar1, "--recalibrate", "kalman", "--out", str(tmp_path / "a")]) == 2
    assert "--recalibrate is an option of the grouped model" in capsys.readouterr().err
    frame = pd.read_csv(SYNTHETIC)
    long = pd.concat([frame.assign(P_mm=p, error_um=frame["error_um"] + 0.01 * p) for p in (0, 100, 200)])
    long.sort_values("time_s", kind="stable").to_csv(tmp_path / "pos.csv", index=False)
    position = ["fit", "--data", str(tmp_path / "pos.csv"), "--position", "P_mm", "--p", "0"]
    assert main([*position, "--recalibrate", "hold", "--out", str(tmp_path / "p")]) == 2
    assert "fit chooses no recalibration section for a position model" in capsys.readouterr().err
    assert not (tmp_path / "a").exists() and not (tmp_path / "p").exists()


def test_diagnose_refuses_to_write_over_its_model_before_it_runs(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    model, _ = synthetic_model()
    path = out / "model_recalibrated.json"
    ModelFile.from_dict(model).save(path)
    before = path.read_bytes()
    monkeypatch.setattr("groupfit.commands.diagnose.ModelFile.load", None)  # the run itself is never reached
    args = ["diagnose", str(path), "--data", str(SYNTHETIC), "--recalibrate", "hold", "--out", str(out), "--force"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert "--out names a file this command reads" in err and len(err.splitlines()) == 1
    assert path.read_bytes() == before


def test_a_check_between_two_samples_falls_on_the_later_one_and_says_so(tmp_path, model_path, capsys):
    result = replay_json(tmp_path, model_path, "--data", SYNTHETIC, "--probe-every", 1000, "--probe-first", 250)
    assert result["probes"]["checks"][0]["i"] == 4  # 2.5 periods after the first sample: the 3rd after it, not the 2nd
    assert result["probes"]["first_check_s"] == 300.0
    assert "the first at 300 s (250 s asked, rounded to whole samples)" in capsys.readouterr().out
    every = replay_json(tmp_path, model_path, "--data", SYNTHETIC, "--probe-every", 250)
    assert every["probes"]["every_s"] == 300.0  # a half rounded up, as the first check is


def test_the_filter_is_chosen_with_checks_on_a_run_measured_on_some_rows(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.loc[np.arange(len(frame)) % 10 != 0, "error_um"] = np.nan  # a probe cycle every 1000 s, 14.75 h
    frame.to_csv(tmp_path / "sparse.csv", index=False)
    assert main(["fit", "--data", str(tmp_path / "sparse.csv"), "--out", str(tmp_path / "m"), "--quiet"]) == 0
    chosen = json.loads((tmp_path / "m" / "model.json").read_text())["recalibration"]["chosen"]
    assert chosen["intervals_s"] == [900.0, 1800.0, 3600.0, 7200.0]  # held-out stretches of 4.4 h and more
    # a check due on an unmeasured row falls on the next reading: the hold serves otherwise than no checks
    assert all(h != n for h, n in zip(chosen["rms_hold_um"], chosen["rms_none_by_interval_um"]))


def test_compare_says_where_its_first_check_falls(tmp_path, capsys):
    args = ["compare", "--data", str(DATASETS / "paper_cycle.csv")]
    args += ["--validate", str(DATASETS / "validation_speed.csv"), "--pmax", "1", "--probe-every", "30m"]
    args += ["--probe-first", "250", "--out", str(tmp_path / "c"), "--quiet"]
    assert main(args) == 0
    assert "so its first check falls 300 s after its start" in capsys.readouterr().out
