"""Logs whose readings come in bursts (a 3-D printer's frame-drift script probes three times a few seconds apart,
about once a minute, and stamps each reading ``2021/06/05-13:24:41``): read as they are, each burst averaged
into one sample on the clock of the bursts' mean period, as ``--resample`` would; a probe's false trigger
left out of its burst's mean. The truth is the same log averaged by hand, burst by burst."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.sampling import burst_cycle

COLUMNS = ["frame_t", "chamber_t", "bed_t"]


def burst_times(n_bursts: int, *, seed: int = 0, readings: int = 3, spacing_s: float = 4.0) -> np.ndarray:
    """Burst starts 60.2 s apart on average with up to ±1.5 s of scheduling jitter, readings ``spacing_s`` apart
    within a burst, stamped to the whole second."""
    rng = np.random.default_rng(seed)
    starts = 60.2 * np.arange(n_bursts) + rng.uniform(-1.5, 1.5, n_bursts)
    return np.round((starts[:, None] + spacing_s * np.arange(readings)[None, :]).ravel())


def printer_log(n_bursts: int = 150, seed: int = 3, spacing_s: float = 4.0) -> pd.DataFrame:
    """A frame-drift log in bursts of three: the burst's index, stamps with a hyphen between date and time, a
    step count as the error (the frame grows as it warms), temperatures read with noise."""
    rng = np.random.default_rng(seed)
    time = burst_times(n_bursts, seed=seed, spacing_s=spacing_s)
    k = np.repeat(np.arange(n_bursts), 3)
    frame_t = 25.0 + 12.0 * (1.0 - np.exp(-k / 60.0)) + rng.normal(0, 0.03, k.size)
    chamber_t = 27.0 + 20.0 * (1.0 - np.exp(-k / 25.0)) + rng.normal(0, 0.1, k.size)
    bed_t = 60.0 + 45.0 * (1.0 - np.exp(-k / 4.0)) + rng.normal(0, 0.2, k.size)
    steps = -80532.0 - 3.0 * (frame_t - 25.0) + 0.8 * (chamber_t - 27.0) + rng.normal(0, 0.5, k.size)
    stamps = pd.Timestamp("2021-06-05 13:24:41") + pd.to_timedelta(time, unit="s")
    return pd.DataFrame(
        {
            "sample": k,
            "time": stamps.strftime("%Y/%m/%d-%H:%M:%S"),
            "mcu_pos_z": np.round(steps),
            "frame_t": frame_t,
            "chamber_t": chamber_t,
            "bed_t": bed_t,
            "bed_target": 105.0,
        }
    )


def averaged_by_hand(log: pd.DataFrame, period_s: float) -> pd.DataFrame:
    """One row per burst: its readings' mean, on a uniform clock of ``period_s``."""
    means = log.groupby("sample")[["mcu_pos_z", *COLUMNS, "bed_target"]].mean().reset_index(drop=True)
    return means.assign(time_s=period_s * np.arange(len(means)))


def cli(*args) -> int:
    return main([str(a) for a in args])


def fitted(tmp_path: Path, path: Path, *extra) -> tuple[dict, str]:
    report = tmp_path / f"{path.stem}.json"
    options = ["--error", "mcu_pos_z", "--temps", ",".join(COLUMNS), "--p", "0", "--ridge", "0"]
    assert cli("fit", "--data", path, *options, "--recalibrate", "none", "--json", report, *extra) == 0
    return json.loads(report.read_text()), report.name


# ------------------------------------------------------------------------- the clock of bursts


def test_bursts_of_three_are_found_with_their_mean_period():
    time = burst_times(200)
    readings, period = burst_cycle(time)
    starts = time[::3]
    assert readings == 3
    assert period == pytest.approx((starts[-1] - starts[0]) / (starts.size - 1), rel=1e-12)
    assert period == pytest.approx(60.2, abs=0.05)


def test_a_missed_burst_and_a_missed_reading_keep_the_clock():
    time = burst_times(200)
    missed_burst = np.delete(time, [150, 151, 152])  # the 51st burst never came
    missed_reading = np.delete(time, 301)  # one touch of the 101st burst failed
    whole = burst_cycle(time)
    for gappy in (missed_burst, missed_reading):
        readings, period = burst_cycle(gappy)
        assert readings == 3 and period == pytest.approx(whole[1], abs=0.02)


@pytest.mark.parametrize(
    "time",
    [
        np.cumsum(np.tile([0.9, 1.1], 200)),  # a jittering clock: no pause between bursts
        np.concatenate([np.arange(300.0), 400.0 + np.arange(300.0), 800.0 + np.arange(300.0)]),  # gaps
        np.arange(600.0),
    ],
    ids=["alternating-steps", "uniform-with-gaps", "uniform"],
)
def test_a_log_that_is_not_read_in_bursts_is_not_taken_for_one(time):
    assert burst_cycle(time) is None


def test_bursts_whose_clock_wanders_by_half_a_period_are_not_taken_for_one():
    time = burst_times(200)
    time[300:] += 35.0  # the script paused half a minute: the later bursts fall between the earlier clock's
    assert burst_cycle(time) is None


# ------------------------------------------------------------------------- the verbs


@pytest.mark.parametrize("spacing_s", [4.0, 0.4])
def test_a_log_in_bursts_fits_as_the_same_log_averaged_by_hand(tmp_path, capsys, spacing_s):
    log = printer_log(spacing_s=spacing_s)  # 0.4 s: a burst's readings share a stamp written to the second
    path = tmp_path / "frame_temp_v_pos.csv"
    log.to_csv(path, index=False)
    _, period = burst_cycle(burst_times(150, seed=3, spacing_s=spacing_s))
    truth = tmp_path / "by_hand.csv"
    averaged_by_hand(log, period).to_csv(truth, index=False)
    (read, _), (expected, _) = fitted(tmp_path, path, "--out", tmp_path / "a"), fitted(tmp_path, truth)
    out = capsys.readouterr().out
    assert f"the readings come in bursts of 3 every {period:g} s" in out
    np.testing.assert_allclose(read["coefficients"], expected["coefficients"], rtol=1e-9, atol=1e-9)
    assert read["sampling_period_s"] == pytest.approx(period, rel=1e-12)


def test_replay_leaves_a_false_trigger_out_of_its_burst_unless_told_to_keep_it(tmp_path, capsys):
    log = printer_log()
    path = tmp_path / "next.csv"
    glitched = log.copy()
    glitched.loc[61, "mcu_pos_z"] += 1720.0  # a false trigger: one touch of the 21st burst
    glitched.to_csv(path, index=False)
    log.to_csv(tmp_path / "model_run.csv", index=False)
    fitted(tmp_path, tmp_path / "model_run.csv", "--out", tmp_path / "m")
    model = tmp_path / "m" / "model.json"
    capsys.readouterr()
    results = {}
    for keep in (False, True):
        assert cli("replay", model, "--data", path, "--json", "-", *(["--keep-glitches"] if keep else [])) == 0
        results[keep] = json.loads(capsys.readouterr().out)
    clean = averaged_by_hand(log, 60.0)["mcu_pos_z"].to_numpy()
    kept = averaged_by_hand(glitched, 60.0)["mcu_pos_z"].to_numpy()
    without_trigger = glitched.drop(index=61).groupby("sample")["mcu_pos_z"].mean().to_numpy()
    for keep, measured in ((False, without_trigger), (True, kept)):
        samples = results[keep]["samples"]
        residual = np.array([sample["residual_um"] for sample in samples], dtype=float)
        prediction = np.array([sample["prediction_um"] for sample in samples], dtype=float)
        np.testing.assert_allclose(measured - prediction, residual, atol=1e-6)
    assert abs(without_trigger[20] - clean[20]) < 2.0 and kept[20] - clean[20] > 500.0


@pytest.mark.parametrize("joiner", ["-", "_", ", "])
def test_a_date_and_time_joined_otherwise_than_by_a_space_reads_as_the_same_seconds(tmp_path, joiner):
    log = printer_log(40)
    spaced = log.assign(time=log["time"].str.replace("-", " ", regex=False))
    joined = log.assign(time=log["time"].str.replace("-", joiner, regex=False))
    coefficients = []
    for name, frame in (("spaced", spaced), ("joined", joined)):
        frame.to_csv(tmp_path / f"{name}.csv", index=False)
        report, _ = fitted(tmp_path, tmp_path / f"{name}.csv", "--out", tmp_path / name)
        coefficients.append((report["coefficients"], report["sampling_period_s"]))
    assert coefficients[0] == coefficients[1]
