"""An error column whose level or size says it is not a thermal error in µm (:mod:`groupfit.error_level`)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.data import load_run
from groupfit.error_level import INPUT_SPAN_PERCENTILES, LEVEL_FLOOR_UM, SMALLEST_DRIFT_PER_KELVIN_UM

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


def paper_cycle_with(tmp_path: Path, name: str, error: np.ndarray, file: str) -> Path:
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.pop("error_um")
    frame[name] = error
    frame.to_csv(tmp_path / file, index=False)
    return tmp_path / file


def paper_error() -> np.ndarray:
    return pd.read_csv(DATASETS / "paper_cycle.csv")["error_um"].to_numpy()


def test_a_probe_position_millimetres_from_zero_is_read_as_logged_with_a_note_of_the_spec_for_its_drift(tmp_path):
    position_mm = 12.34 + paper_error() / 1000.0  # a probe homed at 12.34 mm, drifting by the thermal error
    data = paper_cycle_with(tmp_path, "probe_z_mm", position_mm, "probe.csv")
    run = load_run(data, temps=["T1", "T2"], error="probe_z_mm")
    np.testing.assert_allclose(run.error, position_mm * 1000.0)
    notes = [note for note in run.notes if "a position from the machine's zero" in note]
    assert len(notes) == 1 and "--error 'probe_z_mm-start' reads the drift" in notes[0]
    drift = load_run(data, temps=["T1", "T2"], error="probe_z_mm-start")
    np.testing.assert_allclose(drift.error, paper_error() - paper_error()[0], atol=1e-9)
    assert not any("machine's zero" in note for note in drift.notes)


def test_a_step_count_from_the_machines_zero_is_noted_with_the_spec_that_reads_its_drift_in_micrometres(tmp_path):
    """A 3-D printer's probe position in steps of 2.5 µm from the machine's zero: the note's spec with the
    factor, written with the start first as a user may write it, reads the drift in µm."""
    steps = -89869.0 + paper_error() / 2.5
    data = paper_cycle_with(tmp_path, "mcu_pos_z", steps, "steps.csv")
    notes = [note for note in load_run(data, temps=["T1", "T2"], error="mcu_pos_z").notes if "zero" in note]
    assert len(notes) == 1 and "'mcu_pos_z*K-start' when it counts steps" in notes[0]
    for spec in ("mcu_pos_z*2.5-start", "mcu_pos_z-start*2.5"):
        drift = load_run(data, temps=["T1", "T2"], error=spec)
        np.testing.assert_allclose(drift.error, paper_error() - paper_error()[0], atol=1e-7)


@pytest.mark.parametrize("level_um", [0.0, 0.5 * LEVEL_FLOOR_UM, 300.0])
def test_an_error_near_zero_gets_no_note_of_its_level(tmp_path, level_um):
    error = level_um + paper_error()
    run = load_run(paper_cycle_with(tmp_path, "error_um", error, "near.csv"), temps=["T1", "T2"])
    assert not any("machine's zero" in note for note in run.notes)


def test_a_large_drift_far_from_zero_that_moves_by_more_than_a_tenth_of_its_level_gets_no_note(tmp_path):
    error = 2 * LEVEL_FLOOR_UM + paper_error() * 20  # moves by 480 µm: a tenth of its level or more
    assert np.ptp(error) > 0.1 * np.min(np.abs(error))
    run = load_run(paper_cycle_with(tmp_path, "error_um", error, "large.csv"), temps=["T1", "T2"])
    assert not any("machine's zero" in note for note in run.notes)


def test_an_error_in_mm_that_moves_by_tenths_of_a_mm_under_a_bare_name_gets_a_note_of_its_size(tmp_path):
    error_mm = paper_error() * 10 / 1000.0  # 0.24 mm of drift, read as 0.24 "µm"
    run = load_run(paper_cycle_with(tmp_path, "Z", error_mm, "bare.csv"), temps=["T1", "T2"], error="Z")
    inputs = max(np.diff(np.percentile(run.temps[:, j], INPUT_SPAN_PERCENTILES))[0] for j in range(2))
    per_kelvin = np.ptp(run.error) / inputs
    assert per_kelvin < SMALLEST_DRIFT_PER_KELVIN_UM
    assert any(f"{per_kelvin:.2g} µm per K" in note and "--error 'Z*1000'" in note for note in run.notes)
    scaled = load_run(paper_cycle_with(tmp_path, "Z", error_mm, "bare.csv"), temps=["T1", "T2"], error="Z*1000")
    np.testing.assert_allclose(scaled.error, paper_error() * 10, rtol=1e-12)
    assert not any("µm per K" in note for note in scaled.notes)


def test_a_thermal_error_in_um_gets_no_note_of_its_size():
    for name in ("paper_cycle", "validation_speed", "repeat_warm", "diag_speed_model"):
        run = load_run(DATASETS / f"{name}.csv", temps=["T1", "T2"])
        assert not any("µm per K" in note for note in run.notes), name


def test_a_temperature_glitch_does_not_make_an_error_in_um_look_like_one_in_mm(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.loc[100, "T2"] = 450.0  # one glitch: 430 K of span for a sample
    frame.to_csv(tmp_path / "glitch.csv", index=False)
    run = load_run(tmp_path / "glitch.csv", temps=["T1", "T2"])
    assert not any("µm per K" in note for note in run.notes)
