"""``replay`` names the samples where the rate limit held the compensation away from its target after the
output had reached it, and the error the output as served leaves."""

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
    assert main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--p", "0", "--quiet", "--out", str(out)]) == 0
    return out / "model.json"


def replayed(model: Path, data: Path, capsys) -> dict:
    capsys.readouterr()
    assert main(["replay", str(model), "--data", str(data), "--json", "-"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_ramp_after_a_sensor_fault_is_counted_and_its_error_as_served_given(tmp_path, model, capsys):
    frame = pd.read_csv(DATASETS / "validation_timing.csv")
    frame.loc[200:239, "T1"] = np.nan  # beyond the hold: a sensor fault, the prediction back from 0 after it
    frame.to_csv(tmp_path / "fault.csv", index=False)
    result = replayed(model, tmp_path / "fault.csv", capsys)
    samples = result["samples"]
    compensation = np.array([s["compensation_um"] for s in samples])
    prediction = np.array([s["prediction_um"] for s in samples])
    faulted = np.array([s["fault"] & 2 != 0 for s in samples])
    lagging = ~faulted & (np.abs(compensation + prediction) > 0.01) & (np.arange(len(samples)) > 0)
    assert lagging.sum() > 0 and result["rate_limited"]["samples"] == int(lagging.sum())
    served = frame["error_um"].to_numpy() + compensation
    assert result["rate_limited"]["rms_as_served_um"] == pytest.approx(np.sqrt(np.mean(served[~faulted] ** 2)))
    assert result["rate_limited"]["rms_as_served_um"] > result["rms_um"]
    assert any("the rate limit held the compensation away from its target" in note for note in result["notes"])


def test_a_run_whose_output_follows_its_target_after_power_on_has_no_such_count(model, capsys):
    result = replayed(model, DATASETS / "validation_timing.csv", capsys)
    assert "rate_limited" not in result
