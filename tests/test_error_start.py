"""``--error COLUMN-start``: an error logged from another zero (a probe's position, a sensor's stand-off) read as
the drift since the run's first reading, and in the rest of a recording since the recording's first reading."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.model import ModelFile

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
STEP_UM = 2.5
SPEC = f"mcu_pos_z*{STEP_UM}-start"


def as_positions(frame: pd.DataFrame, zero_steps: float) -> pd.DataFrame:
    """The run with its error logged as a printer logs its probe: in steps, from the machine's zero."""
    return frame.assign(mcu_pos_z=frame["error_um"] / STEP_UM + zero_steps).drop(columns="error_um")


def from_first(frame: pd.DataFrame, first: float | None = None) -> pd.DataFrame:
    """The truth: the run with its error in µm less the first reading of its recording (its own by default)."""
    return frame.assign(error_um=frame["error_um"] - (frame["error_um"].iloc[0] if first is None else first))


def write(frame: pd.DataFrame, path: Path) -> Path:
    frame.to_csv(path, index=False)
    return path


def fit(tmp_path: Path, data: Path, error: str, name: str) -> Path:
    out = tmp_path / name
    args = ["fit", "--data", str(data), "--temps", "T1,T2", "--error", error, "--p", "2", "--search", "exact"]
    assert main([*args, "--out", str(out), "--quiet"]) == 0
    return out / "model.json"


def replay(model: Path, data: Path, *extra: str) -> dict:
    out = model.parent / f"replay_{data.stem}_{len(list(model.parent.iterdir()))}.json"
    assert main(["replay", str(model), "--data", str(data), *extra, "--json", str(out)]) == 0
    return json.loads(out.read_text())


def residuals(result: dict) -> np.ndarray:
    return np.array([s["residual_um"] for s in result["samples"]], dtype=float)


@pytest.mark.parametrize("spec", [SPEC, f"mcu_pos_z-start*{STEP_UM}", f"mcu_pos_z - start * {STEP_UM}"])
def test_runs_homed_to_other_zeros_give_the_model_and_the_replay_of_their_drift_since_the_start(tmp_path, spec):
    model_run = pd.read_csv(DATASETS / "paper_cycle.csv")
    next_run = pd.read_csv(DATASETS / "repeat_timing.csv")
    raw = fit(tmp_path, write(as_positions(model_run, -89869.0), tmp_path / "a.csv"), spec, "raw")
    truth = fit(tmp_path, write(from_first(model_run), tmp_path / "a_truth.csv"), "error_um", "truth")
    fitted, expected = ModelFile.load(raw), ModelFile.load(truth)
    assert fitted.error == spec
    np.testing.assert_allclose(fitted.coefficients, expected.coefficients, rtol=1e-7, atol=1e-7)
    assert fitted.training["recordings"][0]["error_zero_um"] == pytest.approx(
        (model_run["error_um"].iloc[0] / STEP_UM - 89869.0) * STEP_UM, rel=1e-12
    )
    rehomed = write(as_positions(next_run, -91234.5), tmp_path / "b.csv")  # another zero, 3.4 mm away
    got = replay(raw, rehomed, "--probe-every", "3600")
    want = replay(truth, write(from_first(next_run), tmp_path / "b_truth.csv"), "--probe-every", "3600")
    np.testing.assert_allclose(residuals(got), residuals(want), atol=1e-7)
    assert got["rms_um"] == pytest.approx(want["rms_um"], rel=1e-7) and got["rms_um"] < 1.0
    assert "constant_offset_um" not in got
    logged_checks = replay(raw, rehomed, "--probe-every", "3600", "--probe-column", spec)  # the checks as logged
    np.testing.assert_allclose(residuals(logged_checks), residuals(want), atol=1e-7)


def test_the_rest_of_a_recording_reads_its_error_from_the_recordings_first_reading(tmp_path, capsys):
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    cut = int(0.6 * len(whole))
    positions = as_positions(whole, -89869.0)
    first_part = write(positions.iloc[:cut], tmp_path / "part1.csv")
    model = fit(tmp_path, first_part, SPEC, "raw")
    truth = fit(tmp_path, write(from_first(whole).iloc[:cut], tmp_path / "truth1.csv"), "error_um", "truth")
    rest_truth = write(from_first(whole).iloc[cut:], tmp_path / "truth2.csv")
    want = residuals(replay(truth, rest_truth))
    assert np.sqrt(np.mean(want**2)) < 1.0  # the recording's drift is well modelled: an offset would show

    by_clock = replay(model, write(positions.iloc[cut:], tmp_path / "part2.csv"))
    assert by_clock["continues"] and by_clock["history_samples"] == cut
    np.testing.assert_allclose(residuals(by_clock), want, atol=1e-7)

    restarted = positions.iloc[cut:].assign(time_s=lambda f: f["time_s"] - f["time_s"].iloc[0])
    given = replay(model, write(restarted, tmp_path / "part2_restarted.csv"), "--continues", str(first_part))
    np.testing.assert_allclose(residuals(given), want, atol=1e-7)

    code = main(["replay", str(model), "--data", str(tmp_path / "part2.csv"), "--probe-column", SPEC])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "is not the recording's start" in err

    first_part.rename(tmp_path / "moved.csv")  # gone: the rule's saved state and the recording's zero stand in
    saved = replay(model, tmp_path / "part2.csv")
    assert not saved["continues"] or saved["continues"] == [str(first_part)]
    np.testing.assert_allclose(residuals(saved), want, atol=1e-7)


def test_compare_scores_the_rest_of_the_recording_from_the_recordings_first_reading(tmp_path):
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    cut = int(0.6 * len(whole))
    positions, truth = as_positions(whole, -89869.0), from_first(whole)
    results = {}
    for name, frame, error in (("raw", positions, SPEC), ("truth", truth, "error_um")):
        parts = [write(frame.iloc[:cut], tmp_path / f"{name}1.csv"), write(frame.iloc[cut:], tmp_path / f"{name}2.csv")]
        out = tmp_path / f"{name}.json"
        args = ["compare", "--data", str(parts[0]), "--validate", str(parts[1]), "--temps", "T1,T2", "--error", error]
        assert main([*args, "--pmax", "2", "--json", str(out), "--quiet", "--out", str(tmp_path / name)]) == 0
        results[name] = json.loads(out.read_text())
    rows = [[r for r in results[k]["rows"] if r["run"].endswith("2")] for k in ("raw", "truth")]
    assert len(rows[0]) == len(rows[1]) > 0
    for got, want in zip(*rows):
        assert got["rms_um"] == pytest.approx(want["rms_um"], rel=1e-6)
    assert max(r["rms_um"] for r in rows[1]) < 2.0


def test_a_length_named_in_millimetres_is_read_in_micrometres_from_its_start(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    gauge = frame.assign(gauge_mm=frame["error_um"] / 1000.0 + 1.25).drop(columns="error_um")  # a 1.25 mm stand-off
    run = load_run(write(gauge, tmp_path / "gauge.csv"), temps=["T1", "T2"], error="gauge_mm-start")
    np.testing.assert_allclose(run.error, from_first(frame)["error_um"], atol=1e-9)


def test_positions_logged_from_the_machines_zero_are_refused_with_the_spec_that_reads_them(tmp_path, capsys):
    frame = as_positions(pd.read_csv(DATASETS / "paper_cycle.csv"), -89869.0)
    path = write(frame, tmp_path / "steps.csv")
    code = main(
        ["fit", "--data", str(path), "--temps", "T1,T2", "--error", "mcu_pos_z*2.5", "--out", str(tmp_path / "o")]
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and not (tmp_path / "o").exists()
    assert "every reading is beyond the plausible ±100000 µm (row 1: " in err
    assert "a position logged from the machine's zero" in err
    assert f"--error '{SPEC}'" in err


def test_a_model_files_recorded_zero_that_is_not_a_number_is_refused(tmp_path):
    model = fit(
        tmp_path,
        write(as_positions(pd.read_csv(DATASETS / "paper_cycle.csv"), -89869.0), tmp_path / "a.csv"),
        SPEC,
        "raw",
    )
    document = json.loads(model.read_text())
    document["training"]["recordings"][0]["error_zero_um"] = "somewhere"
    model.write_text(json.dumps(document))
    with pytest.raises(InputError, match=r"training.recordings\[0\].error_zero_um must be"):
        ModelFile.load(model)


def test_a_first_reading_that_is_a_marker_is_refused_naming_its_row(tmp_path, capsys):
    frame = as_positions(pd.read_csv(DATASETS / "paper_cycle.csv"), -89869.0)
    frame.loc[:2, "mcu_pos_z"] = -999.0  # a logger's "no reading" on the first rows
    path = write(frame, tmp_path / "marker.csv")
    code = main(["fit", "--data", str(path), "--temps", "T1,T2", "--error", SPEC, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and not (tmp_path / "o").exists()
    assert "read from its first reading (row 1: -2497.5 µm as logged)" in err and "repair or drop that row" in err
