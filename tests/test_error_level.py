"""An error column whose level or size says it is not a thermal error in µm (:mod:`groupfit.error_level`)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.error_level import LEVEL_FLOOR_UM, SMALLEST_DRIFT_PER_KELVIN_UM

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


def paper_cycle_with(tmp_path: Path, name: str, error: np.ndarray, file: str) -> Path:
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.pop("error_um")
    frame[name] = error
    frame.to_csv(tmp_path / file, index=False)
    return tmp_path / file


def paper_error() -> np.ndarray:
    return pd.read_csv(DATASETS / "paper_cycle.csv")["error_um"].to_numpy()


def test_a_probe_position_millimetres_from_zero_is_refused_with_the_way_to_read_its_drift(tmp_path, capsys):
    position_mm = 12.34 + paper_error() / 1000.0  # a probe homed at 12.34 mm, drifting by the thermal error
    data = paper_cycle_with(tmp_path, "probe_z_mm", position_mm, "probe.csv")
    out = tmp_path / "out"
    code = main(["fit", "--data", str(data), "--temps", "T1,T2", "--error", "probe_z_mm", "--out", str(out)])
    message = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(message) == 1
    assert "column 'probe_z_mm'" in message[0] and "--error 'probe_z_mm-start'" in message[0]
    assert not out.exists()
    assert (
        main(
            [
                "fit",
                "--data",
                str(data),
                "--temps",
                "T1,T2",
                "--error",
                "probe_z_mm",
                "--range-error",
                "1e6",
                "--quiet",
                "--out",
                str(out),
            ]
        )
        == 0
    )  # a range given: modelled as logged
    drift = load_run(data, temps=["T1", "T2"], error="probe_z_mm-start")
    np.testing.assert_allclose(drift.error, paper_error() - paper_error()[0], atol=1e-9)


@pytest.mark.parametrize("level_um", [0.0, 0.5 * LEVEL_FLOOR_UM, 300.0])
def test_an_error_near_zero_or_moving_by_its_level_is_read_as_logged(tmp_path, level_um):
    error = level_um + paper_error()
    run = load_run(paper_cycle_with(tmp_path, "error_um", error, "near.csv"), temps=["T1", "T2"])
    np.testing.assert_allclose(run.error, error)


def test_a_large_drift_far_from_zero_that_moves_by_more_than_a_tenth_of_its_level_is_read_as_logged(tmp_path):
    error = 2 * LEVEL_FLOOR_UM + paper_error() * 20  # moves by 480 µm: a tenth of its level or more
    assert np.ptp(error) > 0.1 * np.min(np.abs(error))
    run = load_run(paper_cycle_with(tmp_path, "error_um", error, "large.csv"), temps=["T1", "T2"])
    np.testing.assert_allclose(run.error, error)


def test_an_error_in_mm_that_moves_by_tenths_of_a_mm_under_a_bare_name_gets_a_note_of_its_size(tmp_path):
    error_mm = paper_error() * 20 / 1000.0  # 0.48 mm of drift, read as 0.48 "µm"
    run = load_run(paper_cycle_with(tmp_path, "Z", error_mm, "bare.csv"), temps=["T1", "T2"], error="Z")
    inputs = max(np.ptp(run.temps[:, j]) for j in range(run.temps.shape[1]))
    per_kelvin = np.ptp(run.error) / inputs
    assert per_kelvin < SMALLEST_DRIFT_PER_KELVIN_UM
    assert any(f"{per_kelvin:.2g} µm per K" in note and "--error 'Z*1000'" in note for note in run.notes)
    scaled = load_run(paper_cycle_with(tmp_path, "Z", error_mm, "bare.csv"), temps=["T1", "T2"], error="Z*1000")
    np.testing.assert_allclose(scaled.error, paper_error() * 20, rtol=1e-12)
    assert not any("µm per K" in note for note in scaled.notes)


def test_a_thermal_error_in_um_gets_no_note_of_its_size():
    for name in ("paper_cycle", "validation_speed", "repeat_warm", "diag_speed_model"):
        run = load_run(DATASETS / f"{name}.csv", temps=["T1", "T2"])
        assert not any("µm per K" in note for note in run.notes), name
