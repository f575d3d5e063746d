"""An error column whose name gives another length unit (``error_mm``, ``dZ [mm]``) is read in µm."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.column_values import LARGEST_ERROR_SPAN_UM, SMALLEST_ERROR_SPAN_UM
from groupfit.data import length_unit, load_run

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


@pytest.mark.parametrize(
    "name, unit, scale",
    [
        ("error_mm", "mm", 1000.0),
        ("dZ [mm]", "mm", 1000.0),
        ("Drift (MM)", "mm", 1000.0),
        ("drift_nm", "nm", 1e-3),
        ("error_um", "µm", 1.0),
        ("Abweichung [µm]", "µm", 1.0),
        ("comm", "µm", 1.0),  # "mm" inside a word is no unit
        ("error", "µm", 1.0),
    ],
)
def test_the_unit_is_read_from_the_end_of_the_name(name, unit, scale):
    assert length_unit(name) == (unit, scale)


def in_millimetres(source: Path, target: Path, column: str = "error_mm") -> None:
    frame = pd.read_csv(source)
    frame[column] = frame.pop("error_um") / 1000.0
    frame.to_csv(target, index=False)


def test_a_run_in_mm_loads_as_the_same_run_in_um_with_a_note(tmp_path):
    in_millimetres(DATASETS / "paper_cycle.csv", tmp_path / "mm.csv", "dZ [mm]")
    plain = load_run(DATASETS / "paper_cycle.csv", temps=["T1", "T2"])
    scaled = load_run(tmp_path / "mm.csv", temps=["T1", "T2"], error="dZ [mm]")
    np.testing.assert_allclose(scaled.error, plain.error, rtol=1e-12, atol=1e-12)
    assert any("'dZ [mm]' is in mm by its name: read ×1000 as µm" in note for note in scaled.notes)
    assert not any("by its name" in note for note in plain.notes)


def test_an_error_in_mm_whose_name_gives_no_unit_is_named_and_its_renamed_column_reads_as_the_run(tmp_path):
    in_millimetres(DATASETS / "paper_cycle.csv", tmp_path / "bare.csv", "dZ")
    bare = load_run(tmp_path / "bare.csv", temps=["T1", "T2"], error="dZ")
    span = np.ptp(bare.error)
    assert 0 < span < SMALLEST_ERROR_SPAN_UM  # a thermal error of some µm, read in mm as µm
    note = f"column 'dZ' spans only {span:.3g} µm over the run, read as µm (its name gives no unit)"
    assert any(note in n and "name it 'dZ_mm'" in n for n in bare.notes)
    in_millimetres(DATASETS / "paper_cycle.csv", tmp_path / "named.csv", "dZ_mm")  # as the note says
    named = load_run(tmp_path / "named.csv", temps=["T1", "T2"], error="dZ_mm")
    plain = load_run(DATASETS / "paper_cycle.csv", temps=["T1", "T2"])
    np.testing.assert_allclose(named.error, plain.error, rtol=1e-12, atol=1e-12)
    assert not any("spans only" in n for n in named.notes + plain.notes)
    frame = pd.read_csv(DATASETS / "paper_cycle.csv").rename(columns={"error_um": "dZ"})
    frame["dZ"] *= 1.01 * SMALLEST_ERROR_SPAN_UM / np.ptp(frame["dZ"])  # just above the smallest span
    frame.to_csv(tmp_path / "least.csv", index=False)
    assert not any("spans only" in n for n in load_run(tmp_path / "least.csv", temps=["T1", "T2"], error="dZ").notes)


def test_an_error_in_nm_whose_name_gives_no_unit_is_named(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame["drift"] = frame.pop("error_um") * 1000.0  # in nm
    frame.to_csv(tmp_path / "nm.csv", index=False)
    run = load_run(tmp_path / "nm.csv", temps=["T1", "T2"], error="drift")
    span = np.ptp(run.error)
    assert span > LARGEST_ERROR_SPAN_UM
    assert any(f"column 'drift' spans {span:.4g} µm" in n and "name it 'drift_nm'" in n for n in run.notes)
    frame.rename(columns={"drift": "drift_nm"}).to_csv(tmp_path / "named.csv", index=False)
    named = load_run(tmp_path / "named.csv", temps=["T1", "T2"], error="drift_nm")
    np.testing.assert_allclose(named.error, run.error / 1000.0, rtol=1e-12)
    assert not any("spans" in n for n in named.notes)


def test_the_plausible_range_applies_in_um(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame["error_mm"] = frame.pop("error_um") / 1000.0
    frame.loc[7, "error_mm"] = 150.0  # 0.15 m: beyond the ±1e5 µm a thermal error can be
    frame.to_csv(tmp_path / "wild.csv", index=False)
    assert main(["fit", "--data", str(tmp_path / "wild.csv"), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert not (tmp_path / "o").exists()


def fit_and_replay(tmp_path: Path, model_csv: Path, next_csv: Path, *probe: str) -> tuple[dict, dict]:
    out = tmp_path / model_csv.stem
    fit = ["fit", "--data", str(model_csv), "--temps", "T1,T2,T3,T4", "--p", "1", "--search", "exact"]
    assert main([*fit, "--out", str(out), "--json", str(out.with_suffix(".json")), "--quiet"]) == 0
    replayed = out.with_suffix(".replay.json")
    assert main(["replay", str(out / "model.json"), "--data", str(next_csv), *probe, "--json", str(replayed)]) == 0
    return json.loads(out.with_suffix(".json").read_text()), json.loads(replayed.read_text())


def test_fit_and_replay_of_a_log_in_mm_give_the_figures_of_the_same_log_in_um(tmp_path):
    in_millimetres(DATASETS / "paper_cycle.csv", tmp_path / "model_mm.csv")
    in_millimetres(DATASETS / "repeat_warm.csv", tmp_path / "next_mm.csv")
    fit_um, replay_um = fit_and_replay(tmp_path, DATASETS / "paper_cycle.csv", DATASETS / "repeat_warm.csv")
    fit_mm, replay_mm = fit_and_replay(tmp_path, tmp_path / "model_mm.csv", tmp_path / "next_mm.csv")
    assert fit_mm["expected_next_run_rms_um"] == pytest.approx(fit_um["expected_next_run_rms_um"], rel=1e-6)
    assert replay_mm["rms_um"] == pytest.approx(replay_um["rms_um"], rel=1e-6)
    np.testing.assert_allclose(
        [s["residual_um"] for s in replay_mm["samples"]], [s["residual_um"] for s in replay_um["samples"]], atol=1e-6
    )


def test_a_probe_column_in_mm_is_read_in_um(tmp_path):
    frame = pd.read_csv(DATASETS / "repeat_warm.csv")
    frame["probe_um"] = frame["error_um"] + 0.5
    frame["probe_mm"] = frame["probe_um"] / 1000.0
    frame.to_csv(tmp_path / "next.csv", index=False)
    replays = []
    for column in ("probe_um", "probe_mm"):
        probe = ("--probe-every", "1800", "--probe-column", column)
        replays.append(fit_and_replay(tmp_path, DATASETS / "paper_cycle.csv", tmp_path / "next.csv", *probe)[1])
    assert replays[0]["probes"]["applied"] > 0
    assert [c["reading_um"] for c in replays[1]["probes"]["checks"]] == pytest.approx(
        [c["reading_um"] for c in replays[0]["probes"]["checks"]], rel=1e-9
    )
    assert replays[1]["rms_um"] == pytest.approx(replays[0]["rms_um"], rel=1e-9)
