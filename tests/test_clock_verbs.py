"""Every verb that reads runs reads their clock alike: ``--period-tolerance`` and ``--resample SECONDS``.

``fit``, ``compare``, ``replay`` and ``diagnose`` are tested in
tests/test_real_logs.py; here the others: ``screw identify / predict /
compare``, ``replay`` of a ball-screw or an AR(1) model, ``fit --model ar1``,
``sweep`` (flags and the study's ``[data]`` keys) and ``fit --position``.
Each log is made from a file with a uniform clock, so that the file itself is
the truth: a jittered copy (stamps moved by up to 0.6 % of the period) is
taken with a note and scores as the file does; a copy with three readings per
period (offsets -d, 0, +d around each value) is read as bursts and, as with
``--resample``, scores as the file does.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.position import load_position_run
from groupfit.sweep.config import read_study
from groupfit.sweep.runs import execute_run

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
SCREW = DATASETS / "screw_A.csv"
ROD = DATASETS / "rod_ar1.csv"
CYCLE = DATASETS / "synthetic_cycle.csv"


def period_of(path: Path) -> float:
    return float(np.median(np.diff(pd.read_csv(path)["time_s"])))


def jittered(path: Path, out: Path, share: float = 0.006, seed: int = 5) -> Path:
    """The file with every time stamp but the first moved by up to ``share`` of the period."""
    frame = pd.read_csv(path)
    period = period_of(path)
    moves = np.random.default_rng(seed).uniform(-share, share, len(frame)) * period
    moves[0] = 0.0
    frame["time_s"] = frame["time_s"] + moves
    frame.to_csv(out, index=False)
    return out


def three_readings(path: Path, out: Path, warm: tuple[str, ...]) -> Path:
    """Three readings per period, 0.2 periods apart, the ``warm`` columns read 0.01 below, at and above each value
    (their mean is the value)."""
    frame = pd.read_csv(path)
    period = period_of(path)
    copies = []
    for step in (-1, 0, 1):
        copy = frame.copy()
        copy["time_s"] = copy["time_s"] + 0.2 * period * step
        for column in warm:
            copy[column] = copy[column] + 0.01 * step
        copies.append(copy)
    pd.concat(copies).sort_values("time_s", kind="stable").to_csv(out, index=False)
    return out


def run_json(capsys, *args) -> tuple[dict, str]:
    """The verb's JSON on stdout and its report on stderr."""
    capsys.readouterr()
    assert main([str(a) for a in args]) == 0
    captured = capsys.readouterr()
    return json.loads(captured.out), captured.err


def read_as_bursts(capsys, *args) -> dict:
    """The verb's JSON on a log of three readings per period, which it reads as bursts (with a note)."""
    result, report = run_json(capsys, *args)
    assert "the readings come in bursts of 3 every" in report
    return result


def refused(capsys, *args) -> str:
    capsys.readouterr()
    assert main([str(a) for a in args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    return err


# ------------------------------------------------------------------------- the ball screw


@pytest.fixture(scope="module")
def screw_model(tmp_path_factory):
    out = tmp_path_factory.mktemp("screw")
    assert main(["screw", "identify", str(SCREW), "--out", str(out)]) == 0
    return out / "screw_model.json"


def screw_sensors() -> tuple[str, ...]:
    return tuple(c for c in pd.read_csv(SCREW, nrows=1).columns if c.startswith("T"))


def test_screw_predict_takes_a_jittered_clock_with_a_note_and_resamples_three_readings(screw_model, tmp_path, capsys):
    predict = ["screw", "predict", screw_model, "--source", "screw_A", "--json", "-", "--data"]
    truth, _ = run_json(capsys, *predict, SCREW)
    jitter, report = run_json(capsys, *predict, jittered(SCREW, tmp_path / "jitter.csv"))
    assert "note" in report and "largest deviation" in report
    assert jitter["metrics"]["max_um"] == pytest.approx(truth["metrics"]["max_um"], rel=0.05)
    three = three_readings(SCREW, tmp_path / "three.csv", screw_sensors())
    resampled, report = run_json(capsys, *predict, three, "--resample", period_of(SCREW))
    assert f"{3 * len(truth['time_s'])} reading(s) averaged" in report
    for result in (resampled, read_as_bursts(capsys, *predict, three)):
        assert result["predicted_error_um"] == pytest.approx(truth["predicted_error_um"], abs=1e-9)
        for key in ("max_um", "rms_um", "max_temp_K", "rms_temp_K"):
            assert result["metrics"][key] == pytest.approx(truth["metrics"][key], abs=1e-9)


def test_screw_identify_and_compare_resample_and_widen_the_tolerance(screw_model, tmp_path, capsys):
    three = three_readings(SCREW, tmp_path / "screw_A.csv", screw_sensors())  # the same stem: the same source
    period = period_of(SCREW)
    truth = json.loads(Path(screw_model).read_text())
    identified, _ = run_json(
        capsys, "screw", "identify", three, "--resample", period, "--out", tmp_path / "i", "--json", "-"
    )
    assert identified["h_W_m2K"] == pytest.approx(truth["h_W_m2K"], rel=1e-9)
    late = jittered(SCREW, tmp_path / "late.csv", share=0.03)  # intervals up to 6 % off the period
    other = DATASETS / "screw_B.csv"
    compare = ["screw", "compare", SCREW, "--validate", late, other, "--out", tmp_path / "c", "--json", "-"]
    assert "--period-tolerance PERCENT" in refused(capsys, *compare)
    result, report = run_json(capsys, *compare, "--period-tolerance", "7")
    assert "largest deviation" in report and {row["run"] for row in result["rows"]} == {"screw_A", "late", "screw_B"}


def test_replay_of_a_screw_model_reads_the_clock_as_the_other_verbs(screw_model, tmp_path, capsys):
    three = three_readings(SCREW, tmp_path / "three.csv", screw_sensors())
    truth, _ = run_json(capsys, "replay", screw_model, "--data", SCREW, "--json", "-")
    resampled, _ = run_json(
        capsys, "replay", screw_model, "--data", three, "--resample", period_of(SCREW), "--json", "-"
    )
    bursts = read_as_bursts(capsys, "replay", screw_model, "--data", three, "--json", "-")
    assert resampled["rms_um"] == pytest.approx(truth["rms_um"], abs=1e-9)
    assert bursts["rms_um"] == pytest.approx(truth["rms_um"], abs=1e-9)


# ------------------------------------------------------------------------- AR(1)


def test_fit_and_replay_of_an_ar1_model_resample_three_readings(tmp_path, capsys):
    fit = ["fit", "--model", "ar1", "--heat", "q_W_m2", "--heat-exponent", "1", "--quiet", "--json", "-"]
    truth, _ = run_json(capsys, *fit, "--data", ROD, "--out", tmp_path / "a")
    three = three_readings(ROD, tmp_path / "three.csv", ("error_um",))
    resampled, report = run_json(capsys, *fit, "--data", three, "--resample", period_of(ROD), "--out", tmp_path / "c")
    assert "averaged" in report
    for result in (resampled, read_as_bursts(capsys, *fit, "--data", three, "--out", tmp_path / "b")):
        assert result["c1"] == pytest.approx(truth["c1"], rel=1e-9)
        assert result["c2_um"] == pytest.approx(truth["c2_um"], rel=1e-9)
    replay = ["replay", tmp_path / "a" / "model.json", "--json", "-", "--data"]
    replayed, _ = run_json(capsys, *replay, ROD)
    again, _ = run_json(capsys, *replay, three, "--resample", period_of(ROD))
    assert again["prediction_um"] == pytest.approx(replayed["prediction_um"], abs=1e-9)
    assert again["scores"]["rms_um"] == pytest.approx(replayed["scores"]["rms_um"], abs=1e-9)


# ------------------------------------------------------------------------- sweep


def write_study(folder: Path, data: Path, extra: str = "") -> Path:
    config = folder / f"{data.stem}.toml"
    config.write_text(
        f'[data]\npath = "{data.as_posix()}"\ntemps = ["T1", "T2"]\n{extra}\n[grid]\np = [2]\nsearch = ["exact"]\n',
        encoding="utf-8",
    )
    return config


def test_a_sweep_study_resamples_by_its_data_key_or_the_flag(tmp_path, capsys):
    three = three_readings(CYCLE, tmp_path / "three.csv", ("T1", "T2"))
    period = period_of(CYCLE)
    (truth,) = read_study(write_study(tmp_path, CYCLE)).runs
    assert set(truth.spec["data"]) == {"sha256", "time", "error"}  # a study without the keys keeps its hashes
    (resampled,) = read_study(write_study(tmp_path, three, f"resample_s = {period:g}")).runs
    assert resampled.spec["data"]["resample_s"] == period
    direct, again = execute_run(truth.spec, truth.path), execute_run(resampled.spec, resampled.path)
    assert again["breaks"] == direct["breaks"]
    assert again["objective"] == pytest.approx(direct["objective"], rel=1e-9)

    plain = write_study(tmp_path, three)
    (bursts,) = read_study(plain).runs  # without the key, the three readings are read as bursts
    read = execute_run(bursts.spec, bursts.path)
    assert read["breaks"] == direct["breaks"] and read["objective"] == pytest.approx(direct["objective"], rel=1e-9)
    sweep = ["sweep", plain, "--db", tmp_path / "s.sqlite", "--quiet", "--workers", "1", "--json", "-"]
    done, report = run_json(capsys, *sweep, "--resample", period)
    assert done["done"] == 1 and done["failed"] == 0 and "averaged" in report
    with pytest.raises(InputError, match=r"config key 'data.resample_s': must be positive, got -1"):
        read_study(write_study(tmp_path, three, "resample_s = -1"))


def test_a_sweep_study_widens_the_tolerance_by_its_data_key(tmp_path):
    late = jittered(CYCLE, tmp_path / "late.csv", share=0.03)
    with pytest.raises(InputError, match=r"--period-tolerance PERCENT"):
        read_study(write_study(tmp_path, late))
    (run,) = read_study(write_study(tmp_path, late, "period_tolerance = 7")).runs
    assert run.spec["data"]["period_tolerance"] == pytest.approx(0.07)
    assert execute_run(run.spec, run.path)["breaks"]


# ------------------------------------------------------------------------- fit --position


def test_a_position_run_refuses_resampling_with_what_to_do():
    frame = pd.DataFrame({"time_s": [0, 0, 60, 60], "T1": [20, 20, 21, 21], "x_mm": [0, 100, 0, 100], "error_um": 0})
    with pytest.raises(InputError, match=r"would mix a check run's positions.*leave --resample out"):
        load_position_run(frame, "x_mm", temps=["T1"], resample=60.0)
