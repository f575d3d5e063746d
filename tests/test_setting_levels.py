"""A setting read back with noise (a spindle speed logged as 2498…2502 r/min) is read by its levels."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.heldout.check import held_out_folds
from groupfit.heldout.folds import make_folds, operating_columns
from groupfit.heldout.nextrun import forward_chaining
from groupfit.setting_levels import MAX_MISSED_FRACTION, held_setting, setting_levels

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
PAPER = DATASETS / "paper_cycle.csv"
PROGRAMME = np.repeat([0.0, 1250.0, 2500.0, 3750.0, 5000.0, 2500.0, 0.0], 60)


def read_back(levels: np.ndarray, sigma: float, seed: int = 0) -> np.ndarray:
    """The levels as a drive reports them: whole r/min with noise, 0 when stopped."""
    noise = np.random.default_rng(seed).normal(0.0, sigma, len(levels)).round()
    return np.where(levels > 0, levels + noise, 0.0)


def test_a_clean_setting_is_its_own_levels():
    np.testing.assert_array_equal(setting_levels(PROGRAMME), PROGRAMME)


@pytest.mark.parametrize("sigma", [1.0, 5.0, 10.0])
def test_a_noisy_setting_is_read_as_the_levels_it_was_set_to(sigma):
    noisy = read_back(PROGRAMME, sigma)
    levels = setting_levels(noisy)
    assert np.all(np.abs(levels - PROGRAMME) <= 4.0 * sigma / np.sqrt(60) + 1.0)  # the median of its level
    np.testing.assert_array_equal(np.flatnonzero(np.diff(levels)), np.flatnonzero(np.diff(PROGRAMME)))
    frame = pd.DataFrame({"speed": noisy})
    assert operating_columns(frame, ["speed"]) == ["speed"]
    clean = make_folds([pd.DataFrame({"speed": PROGRAMME})], ["speed"])
    folds = make_folds([frame], ["speed"])
    assert folds.kind == clean.kind == "condition"
    np.testing.assert_array_equal(folds.labels, clean.labels)


def test_readings_on_a_ramp_between_levels_are_read_as_the_level_it_reaches():
    steps = np.flatnonzero(np.diff(PROGRAMME)) + 1
    ramped = PROGRAMME.copy()
    for i in steps:  # a drive taking four samples to reach the new speed
        ramped[i : i + 4] = PROGRAMME[i - 1] + (PROGRAMME[i] - PROGRAMME[i - 1]) * np.arange(1, 5) / 5
    noisy = read_back(ramped, 3.0, seed=6)
    levels = setting_levels(noisy)
    assert set(np.unique(levels).round(-1)) == set(np.unique(PROGRAMME))
    changes = np.flatnonzero(np.diff(levels)) + 1
    np.testing.assert_array_equal(changes, steps)  # the setting changed when the ramp began
    assert operating_columns(pd.DataFrame({"speed": noisy}), ["speed"]) == ["speed"]


@pytest.mark.parametrize(
    "name, values",
    [
        ("a ramp", np.linspace(0.0, 5000.0, 420)),
        ("a noisy drifting ambient", 20 + np.cumsum(np.random.default_rng(2).normal(0, 0.05, 420))),
        ("two regimes with more spread than noise", np.repeat([18.0, 24.0], 210) + np.sin(np.arange(420)) * 0.4),
    ],
)
def test_readings_that_do_not_fall_into_tight_levels_are_not_a_setting(name, values):
    assert operating_columns(pd.DataFrame({"x": values}), ["x"]) == []
    np.testing.assert_array_equal(setting_levels(values), values)


def test_fit_reads_a_noisy_speed_column_as_the_clean_one(tmp_path):
    frame = pd.read_csv(PAPER)
    noisy = frame.assign(speed_rpm=read_back(frame["speed_rpm"].to_numpy(dtype=float), 3.0, seed=4))
    assert (noisy["speed_rpm"] != frame["speed_rpm"]).mean() > 0.5
    expected = {}
    for name, data in (("clean", frame), ("noisy", noisy)):
        path = tmp_path / f"{name}.csv"
        data.to_csv(path, index=False)
        report = tmp_path / f"{name}.json"
        args = ["fit", "--data", str(path), "--recalibrate", "none", "--quiet", "--json", str(report)]
        assert main([*args, "--out", str(tmp_path / name)]) == 0
        fitted = json.loads(report.read_text())
        expected[name] = (fitted["expected_next_run_rms_um"], fitted["expected_next_run_method"])
    assert expected["noisy"] == expected["clean"]
    assert "operating segments (changes of speed_rpm" in expected["noisy"][1]


def test_compare_reads_the_conditions_and_the_ar1_heat_levels_of_a_noisy_speed_as_the_clean_ones():
    from groupfit.conditions import condition_changes, run_condition
    from groupfit.data import load_run
    from groupfit.models.ar1 import AR1Model

    datasets = PAPER.parent
    clean = {name: pd.read_csv(datasets / f"{name}.csv") for name in ("paper_cycle", "repeat_timing")}
    runs = {}
    for seed, (name, frame) in enumerate(clean.items()):
        noisy = frame.assign(speed_rpm=read_back(frame["speed_rpm"].to_numpy(dtype=float), 3.0, seed=seed))
        runs[name] = (load_run(frame, temps=["T1", "T2"]), load_run(noisy, temps=["T1", "T2"]))
    (model_clean, model_noisy), (next_clean, next_noisy) = runs["paper_cycle"], runs["repeat_timing"]
    columns = ("speed_rpm",)
    assert condition_changes(model_noisy, columns) == condition_changes(model_clean, columns)
    assert run_condition(next_noisy, model_noisy, columns, 5) == run_condition(next_clean, model_clean, columns, 5)
    assert run_condition(next_clean, model_clean, columns, 5) == "same condition"
    fitted = {}
    for label, run in (("clean", model_clean), ("noisy", model_noisy)):
        heat = run.frame["speed_rpm"].to_numpy(dtype=float)[:, None]
        fitted[label] = AR1Model().fit(heat, run.error)
    assert fitted["noisy"].c1_ == pytest.approx(fitted["clean"].c1_, rel=1e-12)
    assert len(fitted["noisy"].c2_) == len(fitted["clean"].c2_)  # one C2 per level set, not per reading
    for (level, c2), (clean_level, clean_c2) in zip(
        sorted(fitted["noisy"].c2_.items()), sorted(fitted["clean"].c2_.items())
    ):
        assert level == pytest.approx(clean_level, rel=0.01) and c2 == pytest.approx(clean_c2, rel=1e-12)


def test_a_missed_reading_of_a_setting_is_held_at_the_one_before():
    rng = np.random.default_rng(7)
    values = np.repeat(rng.choice([0.0, 1250.0, 2500.0, 3750.0], 12), 25)
    for missed in ([0, 1, 140], [299], [60, 61, 62]):
        gappy = values.copy()
        gappy[missed] = np.nan
        expected = pd.Series(gappy).ffill().bfill().to_numpy()
        np.testing.assert_array_equal(held_setting(gappy), expected)
    too_many = values.copy()
    too_many[: int(MAX_MISSED_FRACTION * values.size) + 1] = np.nan
    assert held_setting(too_many) is None and held_setting(np.full(5, np.nan)) is None
    assert held_setting(values) is values or np.array_equal(held_setting(values), values)


@pytest.mark.parametrize("mark", ["", "---"])
def test_a_speed_with_a_missed_reading_still_cuts_the_next_run_estimate_into_its_segments(tmp_path, mark):
    frame = pd.read_csv(DATASETS / "validation_speed.csv").drop(columns=["spindle_on"])
    level_rows = np.flatnonzero(np.r_[False, np.diff(frame["speed_rpm"]) == 0])  # not at a change of speed
    gappy = frame.astype({"speed_rpm": object})
    gappy.loc[level_rows[[10, 200]], "speed_rpm"] = mark
    paths = {name: tmp_path / f"{name}.csv" for name in ("clean", "gappy")}
    frame.to_csv(paths["clean"], index=False)
    gappy.to_csv(paths["gappy"], index=False)
    runs = {name: load_run(path, temps=["T1", "T2"]) for name, path in paths.items()}
    scores = {name: forward_chaining(run, [0, 1]) for name, run in runs.items()}
    assert "changes of speed_rpm" in scores["gappy"].segments and not scores["gappy"].blocks_of_time
    np.testing.assert_array_equal(scores["gappy"].counts, scores["clean"].counts)
    np.testing.assert_allclose(scores["gappy"].sse, scores["clean"].sse, rtol=1e-12)
    exclude = {"time_s", "error_um", "T1", "T2"}
    folds = {name: held_out_folds([run.frame], exclude, run.error) for name, run in runs.items()}
    assert folds["gappy"].kind == folds["clean"].kind == "condition"
    np.testing.assert_array_equal(folds["gappy"].labels, folds["clean"].labels)
