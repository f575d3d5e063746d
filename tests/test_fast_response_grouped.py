"""The fast-response stage of a grouped model: one set of gains shared by the groups, each group's own slopes kept
and recovered exactly, computed by the run-time rule as offline."""

import json

import numpy as np
import pandas as pd
import pytest
from test_fast_response import PERIOD_S, SENSORS, exponential_lag

from groupfit.cli import main
from groupfit.fast_response import stage_of, with_stage, without_stage
from groupfit.fast_response_choice import choose_stage
from groupfit.model import ModelFile
from groupfit.model import model_file_problem as model_problem
from groupfit.training_checks import FAST_KEY


def two_regime_run(seed: int, *, n: int = 1600) -> pd.DataFrame:
    """A warm-up whose slow response changes weights half-way (the spindle's bearings take over: the grouped
    model's case), each sensor with a swing of its own; the error weighs the first sensor's swing by 4 beyond its
    slow weight in both regimes."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * PERIOD_S
    slow = np.column_stack([4 * (1 - np.exp(-t / (3600 * h))) for h in (1.0, 2.5, 5.0)])
    swing = 0.4 * np.sin(2 * np.pi * t[:, None] / np.array([1200.0, 1620.0, 2100.0]) + rng.uniform(0, 6, 3))
    temps = 20 + slow + swing + 0.01 * rng.standard_normal((n, 3))
    weights = np.where(np.arange(n)[:, None] < n // 2, [3.0, -2.0, 1.5], [6.0, -1.0, 0.5])
    error = np.sum((slow + swing) * weights, axis=1) + 4.0 * swing[:, 0] + 0.02 * rng.standard_normal(n)
    frame = pd.DataFrame(temps, columns=SENSORS)
    frame.insert(0, "time_s", t)
    frame["error_um"] = error
    return frame


@pytest.fixture(scope="module")
def grouped(tmp_path_factory):
    folder = tmp_path_factory.mktemp("grouped_fast")
    frame = two_regime_run(1)
    frame.to_csv(folder / "run.csv", index=False)
    args = ["fit", "--data", str(folder / "run.csv"), "--temps", ",".join(SENSORS), "--p", "1", "--reference", "none"]
    assert main([*args, "--recalibrate", "none", "--quiet", "--out", str(folder / "m")]) == 0
    model = ModelFile.load(folder / "m" / "model.json")
    assert model.p == 1 and len(model.coefficients) == 2
    return model, frame


def test_the_groups_share_the_gains_of_the_least_squares_fit_on_the_high_passes(grouped):
    model, frame = grouped
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 600.0)
    temps = frame[SENSORS].to_numpy()
    high = temps - np.column_stack([exponential_lag(temps[:, k], 600.0) for k in range(3)])
    rows = np.asarray(model.coefficients)
    serving = model.serving_groups(len(frame))
    base = rows[serving, 0] + np.einsum("ij,ij->i", rows[serving, 1:], temps)
    gains = np.linalg.lstsq(high, frame["error_um"].to_numpy() - base, rcond=None)[0]
    np.testing.assert_allclose(stage_of(staged)["coefficients"], gains, rtol=1e-6, atol=1e-9)
    in_sample = [np.sqrt(np.mean((frame["error_um"].to_numpy() - b) ** 2)) for b in (base, base + high @ gains)]
    assert in_sample[1] < 0.9 * in_sample[0]  # a part of the swings the groups leave (the groups took the rest)
    # every group: its own slopes raised by the gains, the low-passes' slopes −gains
    staged_rows = np.asarray(staged.coefficients)
    np.testing.assert_allclose(staged_rows[:, 1:4], rows[:, 1:] + gains, rtol=0, atol=1e-12)
    np.testing.assert_allclose(staged_rows[:, 4:], np.tile(-gains, (2, 1)), rtol=0, atol=1e-12)
    assert stage_of(staged)["slopes"] == rows[:, 1:].tolist()
    prediction = staged.predict(staged.inputs(frame))
    np.testing.assert_allclose(prediction, base + high @ gains, rtol=0, atol=1e-9)


def test_without_the_stage_each_group_is_recovered_exactly(grouped, tmp_path):
    model, frame = grouped
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 300.0)
    assert model_problem(staged.to_dict()) is None
    staged.save(tmp_path / "staged.json")
    for candidate in (staged, ModelFile.load(tmp_path / "staged.json")):  # in memory, and read back from its file
        back = without_stage(candidate)
        assert back.coefficients == model.coefficients and back.temps == model.temps
        assert back.switching == model.switching and FAST_KEY not in back.training
    # slopes of the wrong number of groups are refused, naming the stage
    broken = staged.to_dict()
    broken["training"][FAST_KEY]["slopes"] = broken["training"][FAST_KEY]["slopes"][:1]
    found = model_problem(broken)
    assert found is not None and FAST_KEY in found and "one list per group (2)" in found


def test_a_grouped_model_on_several_runs_takes_no_stage(grouped):
    model, frame = grouped
    runs = [(frame, frame["error_um"].to_numpy())] * 2
    assert with_stage(model, runs, 600.0) is None


def test_replay_switches_the_staged_groups_as_offline_and_the_stage_helps_on_a_next_run(grouped, tmp_path):
    model, frame = grouped
    kept, tuning, without = choose_stage(model, [(frame, frame["error_um"].to_numpy())], "auto")
    assert stage_of(kept) is not None and without is not None
    kept.replace(recalibration=tuning.section).save(tmp_path / "staged.json")
    later = two_regime_run(2)
    later.to_csv(tmp_path / "next.csv", index=False)
    out = tmp_path / "replay.json"
    args = ["replay", str(tmp_path / "staged.json"), "--data", str(tmp_path / "next.csv"), "--json", str(out)]
    assert main([*args, "--out", str(tmp_path / "r")]) == 0
    samples = json.loads(out.read_text())["samples"]
    groups = np.array([s["group"] for s in samples]) - 1
    replayed = np.array([s["prediction_um"] for s in samples])
    assert set(groups) == {0, 1}
    np.testing.assert_allclose(replayed, kept.predict(kept.inputs(later), groups, transfer=True), rtol=0, atol=1e-9)
    base = without_stage(kept)
    alone = base.predict(base.inputs(later), groups, transfer=True)
    away = np.abs(np.arange(len(later)) - np.flatnonzero(np.diff(groups))[0]) > 60  # the switch's own step aside
    rms = [np.sqrt(np.mean((later["error_um"].to_numpy() - p)[away] ** 2)) for p in (replayed, alone)]
    assert rms[0] < 0.9 * rms[1]
