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
