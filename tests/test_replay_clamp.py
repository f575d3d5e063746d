"""``replay`` scores what the compensation can correct: a prediction beyond the clamp counts only up to it."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    out = tmp_path_factory.mktemp("model")
    assert main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--p", "1", "--out", str(out), "--quiet"]) == 0
    return out / "model.json"


def clamped_to(model: Path, folder: Path, limit_um: float) -> Path:
    """The model file with its compensation clamped to ±``limit_um``."""
    data = json.loads(model.read_text())
    data["switching"]["comp_min_um"], data["switching"]["comp_max_um"] = -limit_um, limit_um
    path = folder / f"model_{limit_um:g}.json"
    path.write_text(json.dumps(data))
    return path


def replayed(model: Path, folder: Path, capsys, *args: str) -> tuple[dict, str]:
    out = folder / "r.json"
    argv = ["replay", str(model), "--data", str(DATASETS / "repeat_warm.csv"), *args, "--json", str(out)]
    assert main(argv) == 0
    return json.loads(out.read_text()), capsys.readouterr().out


def test_the_residual_counts_the_error_the_clamp_leaves(model, tmp_path, capsys):
    error = pd.read_csv(DATASETS / "repeat_warm.csv")["error_um"].to_numpy()
    free, free_report = replayed(model, tmp_path, capsys)
    prediction = np.array([s["prediction_um"] for s in free["samples"]])
    assert free["clamped_samples"] == 0 and "beyond the compensation's clamp" not in free_report
    np.testing.assert_allclose([s["residual_um"] for s in free["samples"]], error - prediction, atol=1e-9)

    limit = 0.5 * float(np.max(np.abs(prediction)))
    tight, report = replayed(clamped_to(model, tmp_path, limit), tmp_path, capsys)
    assert [s["prediction_um"] for s in tight["samples"]] == list(prediction)  # the model is the same
    beyond = np.abs(prediction) > limit
    assert tight["clamped_samples"] == int(beyond.sum()) > 0
    left = error - np.clip(prediction, -limit, limit)
    np.testing.assert_allclose([s["residual_um"] for s in tight["samples"]], left, atol=1e-9)
    assert tight["rms_um"] == pytest.approx(float(np.sqrt(np.mean(left**2))))
    assert tight["rms_um"] > free["rms_um"]
    assert f"beyond the compensation's clamp [{-limit:g}, {limit:g}] µm on {int(beyond.sum())} sample(s)" in report


def test_probe_checks_carry_the_compensation_beyond_the_models_clamp_by_the_offsets_bound(model, tmp_path, capsys):
    free, _ = replayed(model, tmp_path, capsys)
    prediction = np.array([s["prediction_um"] for s in free["samples"]])
    limit = 0.5 * float(np.max(np.abs(prediction)))
    tight = clamped_to(model, tmp_path, limit)
    bound = json.loads(tight.read_text())["recalibration"]["offset_max_um"]
    unchecked, _ = replayed(tight, tmp_path, capsys)
    checked, _ = replayed(tight, tmp_path, capsys, "--probe-every", "1000")
    compensation = np.abs([s["compensation_um"] for s in checked["samples"]])
    assert np.max(np.abs([s["compensation_um"] for s in unchecked["samples"]])) <= limit
    assert limit < np.max(compensation) <= limit + bound  # beyond the model's clamp, within the checks' bound
    assert checked["rms_um"] < 0.5 * unchecked["rms_um"]


def test_an_integer_register_that_saturates_is_counted_and_scored_beside_the_rule(model, tmp_path, capsys):
    error = pd.read_csv(DATASETS / "repeat_warm.csv")["error_um"].to_numpy()
    free, _ = replayed(model, tmp_path, capsys, "--resolution-um", "0.1")
    prediction = np.array([s["prediction_um"] for s in free["samples"]])
    assert free["register"]["saturated_samples"] == 0
    assert abs(free["register"]["rms_um"] - free["rms_um"]) <= 0.05  # rounding to 0.1 µm counts at most half
    limit_counts = int(0.5 * np.max(np.abs(prediction)) / 0.1)
    tight, report = replayed(model, tmp_path, capsys, "--resolution-um", "0.1", "--counts-limit", str(limit_counts))
    held = limit_counts * 0.1
    beyond = np.abs(prediction) > held
    assert tight["register"]["saturated_samples"] == int(beyond.sum()) > 0
    left = error - np.clip(np.round(prediction / 0.1) * 0.1, -held, held)
    assert tight["register"]["rms_um"] == pytest.approx(float(np.sqrt(np.mean(left**2))), abs=1e-9)
    assert tight["rms_um"] == free["rms_um"]  # the rule's own score is the compensation it asks for
    assert f"saturates at ±{limit_counts} counts" in report and f"on {int(beyond.sum())} of" in report


def test_a_check_interval_that_is_not_whole_samples_is_said_to_be_rounded(model, tmp_path, capsys):
    data, report = replayed(model, tmp_path, capsys, "--probe-every", "250")  # a 100 s run
    assert data["probes"]["every_s"] == 300.0 and data["probes"]["asked_every_s"] == 250.0  # a half rounded up
    times = [s["time_s"] for s in data["samples"] if "probe" in s]
    assert set(np.diff(times)) == {300.0}
    assert "every 300 s (250 s asked, rounded to whole samples)" in report
    exact, report = replayed(model, tmp_path, capsys, "--probe-every", "300")
    assert exact["probes"]["every_s"] == 300.0 and "asked" not in report


def test_compare_scores_a_run_beyond_the_clamp_as_replay_does(tmp_path, capsys):
    """A next run 2.5 times as hot as the modelling run: MLR's prediction passes its clamp on most samples."""
    hot = pd.read_csv(DATASETS / "validation_timing.csv")
    for column in ("T1", "T2"):
        hot[column] = (hot["T_amb"] + (hot[column] - hot["T_amb"]) * 2.5).round(2)
    hot["error_um"] = (hot["error_um"] * 2.5).round(2)
    path = tmp_path / "hot.csv"
    hot.to_csv(path, index=False)
    paper = str(DATASETS / "paper_cycle.csv")
    fit = ["fit", "--data", paper, "--temps", "T1,T2", "--p", "0", "--ridge", "0", "--recalibrate", "none"]
    assert main([*fit, "--out", str(tmp_path / "m"), "--quiet"]) == 0
    replay = ["replay", str(tmp_path / "m" / "model.json"), "--data", str(path)]
    assert main([*replay, "--json", str(tmp_path / "r.json")]) == 0
    replayed = json.loads((tmp_path / "r.json").read_text())
    assert replayed["clamped_samples"] > 0
    capsys.readouterr()
    compare = ["compare", "--data", paper, "--temps", "T1,T2", "--pmax", "1", "--validate", str(path)]
    assert main([*compare, "--json", str(tmp_path / "c.json"), "--out", str(tmp_path / "c"), "--quiet"]) == 0
    rows = json.loads((tmp_path / "c.json").read_text())["rows"]
    mlr = next(r for r in rows if r["model"] == "mlr" and r["run"] == "hot")
    assert mlr["rms_um"] == pytest.approx(replayed["rms_um"], rel=1e-12)
    assert "hot: the predictions of MLR (±" in capsys.readouterr().out
