"""The fast-response stage: the least-squares fit of the model's residual on its inputs' high-passes, kept only when
held-out checks improve, written as low-pass derived inputs and removed exactly."""

import json

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.fast_response import high_passes, stage_of, with_stage, without_stage
from groupfit.fast_response_choice import choose_stage
from groupfit.model import ModelFile
from groupfit.model import model_file_problem as model_problem
from groupfit.training_checks import FAST_KEY

PERIOD_S = 60.0
SENSORS = ["T1", "T2", "T3"]


def exponential_lag(x: np.ndarray, tau_s: float) -> np.ndarray:
    """y[k] = a·y[k−1] + (1 − a)·x[k], y[−1] = x[0]: written out here, not taken from the package."""
    a = np.exp(-PERIOD_S / tau_s)
    y = np.empty_like(x)
    memory = x[0]
    for k, value in enumerate(x):
        memory = a * memory + (1 - a) * value
        y[k] = memory
    return y


def swinging_run(seed: int, *, fast_gain: float, n: int = 1500) -> pd.DataFrame:
    """Slow warm-up of three sensors, each with a swing of its own (20-35 min: a chiller, a pump) on top; the
    error weighs the first sensor's swing with ``fast_gain`` beyond its slow response, plus a little noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * PERIOD_S
    slow = np.column_stack([4 * (1 - np.exp(-t / (3600 * h))) for h in (1.0, 2.5, 5.0)])
    periods = np.array([1200.0, 1620.0, 2100.0])
    swing = 0.4 * np.sin(2 * np.pi * t[:, None] / periods + rng.uniform(0, 6, 3))
    temps = 20 + slow + swing + 0.01 * rng.standard_normal((n, 3))
    weights = np.array([3.0, -2.0, 1.5])
    error = (slow + swing) @ weights + fast_gain * swing[:, 0] + 0.02 * rng.standard_normal(n)
    frame = pd.DataFrame(temps, columns=SENSORS)
    frame.insert(0, "time_s", t)
    frame["error_um"] = error
    return frame


def fitted_model(folder, frame, *extra) -> ModelFile:
    """``groupfit fit`` (global least squares, no reference) on ``frame``; the model file."""
    frame.to_csv(folder / "run.csv", index=False)
    args = ["fit", "--data", str(folder / "run.csv"), "--temps", ",".join(SENSORS), "--p", "0", "--ridge", "0"]
    assert main([*args, "--reference", "none", "--quiet", *extra, "--out", str(folder / "m")]) == 0
    return ModelFile.load(folder / "m" / "model.json")


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    frame = swinging_run(1, fast_gain=4.0)
    return fitted_model(tmp_path_factory.mktemp("fast"), frame, "--recalibrate", "none"), frame


def test_the_stage_is_the_least_squares_fit_of_the_residual_on_the_high_passes(fitted):
    model, frame = fitted
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 600.0)
    temps = frame[SENSORS].to_numpy()
    high = temps - np.column_stack([exponential_lag(temps[:, k], 600.0) for k in range(3)])
    base = model.coefficients[0][0] + temps @ np.asarray(model.coefficients[0][1:])
    gains = np.linalg.lstsq(high, frame["error_um"].to_numpy() - base, rcond=None)[0]
    np.testing.assert_allclose(stage_of(staged)["coefficients"], gains, rtol=1e-6, atol=1e-9)
    # the first sensor's swings weigh 3 + 4 in the error: the model's slope and the stage's gain add up to it
    assert model.coefficients[0][1] + gains[0] == pytest.approx(7.0, rel=0.05)
    # the model file predicts the model plus the stage: inputs @ coefficients
    prediction = np.column_stack([np.ones(len(frame)), staged.inputs(frame)]) @ np.asarray(staged.coefficients[0])
    np.testing.assert_allclose(prediction, base + high @ gains, rtol=0, atol=1e-9)
    np.testing.assert_allclose(high_passes(model, frame, SENSORS, 600.0), high, rtol=0, atol=1e-12)


def test_without_the_stage_the_model_is_recovered_exactly(fitted):
    model, frame = fitted
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 300.0)
    assert len(staged.temps) == 2 * len(SENSORS)
    assert model_problem(staged.to_dict()) is None
    back = without_stage(staged)
    assert back.temps == model.temps and back.derived_inputs == model.derived_inputs
    assert back.switching == model.switching and FAST_KEY not in back.training
    assert back.coefficients == model.coefficients  # bit for bit: diagnose starts from the fit's figures


def test_a_stage_is_kept_only_when_held_out_checks_improve(fitted, tmp_path):
    model, frame = fitted
    kept, tuning, without = choose_stage(model, [(frame, frame["error_um"].to_numpy())], "auto")
    assert stage_of(kept) is not None and without is not None
    assert np.mean(np.log(np.divide(tuning.rms_chosen_um, without.rms_chosen_um))) < -0.02
    # a machine whose error weighs the swings as it weighs the slow rise: nothing for a stage to take
    plain = swinging_run(1, fast_gain=0.0)
    base = fitted_model(tmp_path, plain, "--recalibrate", "none")
    kept, _, without = choose_stage(base, [(plain, plain["error_um"].to_numpy())], "auto")
    assert stage_of(kept) is None and without is None
    # no checks, no stage
    kept, tuning, without = choose_stage(model, [(frame, frame["error_um"].to_numpy())], "none")
    assert stage_of(kept) is None and tuning.section is None


def test_fit_reports_the_stage_and_replay_computes_it(tmp_path, capsys):
    model = fitted_model(tmp_path, swinging_run(2, fast_gain=4.0))
    assert stage_of(model) is not None
    later = swinging_run(3, fast_gain=4.0)
    later.to_csv(tmp_path / "next.csv", index=False)
    out = tmp_path / "replay.json"
    assert (
        main(["replay", str(tmp_path / "m" / "model.json"), "--data", str(tmp_path / "next.csv"), "--json", str(out)])
        == 0
    )
    assert "fast    fast response: each of 3 input(s)" in capsys.readouterr().out
    replayed = np.array([s["prediction_um"] for s in json.loads(out.read_text())["samples"]])
    offline = np.column_stack([np.ones(len(later)), model.inputs(later)]) @ np.asarray(model.coefficients[0])
    np.testing.assert_allclose(replayed, offline, rtol=0, atol=1e-9)
    # on the next run the stage takes the swing the model alone leaves
    base = without_stage(model)
    alone = np.column_stack([np.ones(len(later)), base.inputs(later)]) @ np.asarray(base.coefficients[0])
    rms = [np.sqrt(np.mean((later["error_um"] - p) ** 2)) for p in (replayed, alone)]
    assert rms[0] < 0.8 * rms[1]


def test_diagnose_seeks_effects_on_the_model_without_its_stage(fitted, tmp_path, capsys):
    model, frame = fitted
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 600.0)
    frame.to_csv(tmp_path / "run.csv", index=False)
    reports = []
    for name, m in (("plain", model), ("staged", staged)):
        m.save(tmp_path / f"{name}.json")
        args = ["diagnose", str(tmp_path / f"{name}.json"), "--data", str(tmp_path / "run.csv")]
        assert main([*args, "--json", str(tmp_path / f"{name}_d.json"), "--out", str(tmp_path / name)]) == 0
        reports.append(json.loads((tmp_path / f"{name}_d.json").read_text()))
    assert capsys.readouterr().out.count("fast-response stage is set aside") == 1  # said of the staged model only
    strip = {"model", "model_path", "written"}
    assert {k: v for k, v in reports[0].items() if k not in strip} == {
        k: v for k, v in reports[1].items() if k not in strip
    }


@pytest.mark.parametrize(
    "stage, problem",
    [
        ({"tau_s": 0, "columns": ["T1"], "coefficients": [1.0], "slopes": [1.0]}, "tau_s"),
        ({"tau_s": 600, "columns": ["T9"], "coefficients": [1.0], "slopes": [1.0]}, "'T9'"),
        ({"tau_s": 600, "columns": ["T1"], "coefficients": [1.0, 2.0], "slopes": [1.0]}, "one number per column"),
        ({"tau_s": 600, "columns": ["T1"], "coefficients": ["x"], "slopes": [1.0]}, "finite numbers"),
        ({"tau_s": 600, "columns": ["T1"], "coefficients": [1.0]}, "slopes must hold"),
        ({"tau_s": 600, "columns": ["T1"], "coefficients": [1.0], "slopes": [1.0], "reference": 5}, "reference"),
        ({"tau_s": 600, "columns": ["T1"], "coefficients": [1.0], "slopes": [1.0], "reference": "T_amb"}, "'T_amb~"),
        ("600", "must be an object"),
    ],
)
def test_a_malformed_stage_is_refused_naming_it(fitted, stage, problem):
    model, frame = fitted
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 600.0).to_dict()
    staged["training"][FAST_KEY] = stage
    found = model_problem(staged)
    assert found is not None and FAST_KEY in found and problem in found


def test_over_a_reference_column_the_stage_takes_the_rises_high_passes(tmp_path):
    # the air swings too; the model reads the sensors over it (T_k − T_amb), and so does the stage
    frame = swinging_run(4, fast_gain=4.0)
    t = frame["time_s"].to_numpy()
    air = 20 + 0.3 * np.sin(2 * np.pi * t / 2700.0)
    frame[SENSORS] = frame[SENSORS].to_numpy() + air[:, None]
    frame.insert(4, "T_amb", air)
    frame.to_csv(tmp_path / "run.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "run.csv"), "--temps", ",".join(SENSORS), "--p", "0", "--ridge", "0"]
    assert main([*args, "--reference", "T_amb", "--recalibrate", "none", "--quiet", "--out", str(tmp_path / "m")]) == 0
    model = ModelFile.load(tmp_path / "m" / "model.json")
    assert model.reference == "T_amb"
    staged = with_stage(model, [(frame, frame["error_um"].to_numpy())], 600.0)
    rises = frame[SENSORS].to_numpy() - air[:, None]
    high = rises - np.column_stack(
        [exponential_lag(frame[c].to_numpy(), 600.0) - exponential_lag(air, 600.0) for c in SENSORS]
    )
    base = model.coefficients[0][0] + rises @ np.asarray(model.coefficients[0][1:])
    gains = np.linalg.lstsq(high, frame["error_um"].to_numpy() - base, rcond=None)[0]
    np.testing.assert_allclose(stage_of(staged)["coefficients"], gains, rtol=1e-6, atol=1e-9)
    assert stage_of(staged)["reference"] == "T_amb" and "T_amb~lp600s" in staged.temps
    assert model_problem(staged.to_dict()) is None
    prediction = np.column_stack([np.ones(len(frame)), staged.inputs(frame)]) @ np.asarray(staged.coefficients[0])
    np.testing.assert_allclose(prediction, base + high @ gains, rtol=0, atol=1e-9)
    assert without_stage(staged) == model
    # the held-out refit in two steps sees the same high-passes: the stage helps on held-out stretches
    kept, tuning, without = choose_stage(model, [(frame, frame["error_um"].to_numpy())], "auto")
    assert stage_of(kept) is not None and stage_of(kept)["reference"] == "T_amb"
    assert np.all(np.asarray(tuning.rms_chosen_um) < np.asarray(without.rms_chosen_um))
