"""``--error COLUMN*K``: an error logged in steps, counts or inches (or with the opposite sign) read ×K as µm."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import length_unit, load_run
from groupfit.errors import InputError
from groupfit.model import ModelFile

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
STEP_UM = 2.5
INCH_UM = 25400.0


def logged_as(source: Path, target: Path, column: str, um_per_unit: float) -> None:
    """``source`` with its error in µm replaced by ``column`` in units of ``um_per_unit`` µm."""
    frame = pd.read_csv(source)
    frame[column] = frame.pop("error_um") / um_per_unit
    frame.to_csv(target, index=False)


def fit_and_replay(tmp_path: Path, model_csv: Path, next_csv: Path, *extra: str) -> tuple[dict, dict, Path]:
    out = tmp_path / f"{model_csv.stem}_{len(list(tmp_path.iterdir()))}"
    fit = ["fit", "--data", str(model_csv), "--temps", "T1,T2,T3,T4", "--p", "1", "--search", "exact", *extra]
    assert main([*fit, "--out", str(out), "--json", str(out.with_suffix(".json")), "--quiet"]) == 0
    replayed = out.with_suffix(".replay.json")
    probe = ("--probe-every", "1800")
    assert main(["replay", str(out / "model.json"), "--data", str(next_csv), *probe, "--json", str(replayed)]) == 0
    return json.loads(out.with_suffix(".json").read_text()), json.loads(replayed.read_text()), out / "model.json"


@pytest.mark.parametrize(
    "column, um_per_unit, spec",
    [("mcu_pos_z", STEP_UM, f"mcu_pos_z*{STEP_UM}"), ("Z gauge", -INCH_UM, "Z gauge * -25400")],
)
def test_fit_and_replay_of_a_log_in_other_units_give_the_figures_of_the_log_in_um(tmp_path, column, um_per_unit, spec):
    logged_as(DATASETS / "paper_cycle.csv", tmp_path / "model_units.csv", column, um_per_unit)
    logged_as(DATASETS / "repeat_warm.csv", tmp_path / "next_units.csv", column, um_per_unit)
    fit_um, replay_um, _ = fit_and_replay(tmp_path, DATASETS / "paper_cycle.csv", DATASETS / "repeat_warm.csv")
    fit_k, replay_k, model = fit_and_replay(
        tmp_path, tmp_path / "model_units.csv", tmp_path / "next_units.csv", "--error", spec
    )
    assert ModelFile.load(model).error == spec  # replay reads the next run's column with the same factor
    assert fit_k["expected_next_run_rms_um"] == pytest.approx(fit_um["expected_next_run_rms_um"], rel=1e-9)
    assert replay_k["rms_um"] == pytest.approx(replay_um["rms_um"], rel=1e-9)
    assert replay_k["probes"]["applied"] == replay_um["probes"]["applied"] > 0
    np.testing.assert_allclose(
        [s["residual_um"] for s in replay_k["samples"]], [s["residual_um"] for s in replay_um["samples"]], atol=1e-9
    )


def test_the_run_reads_the_column_times_the_factor_with_a_note(tmp_path):
    logged_as(DATASETS / "paper_cycle.csv", tmp_path / "steps.csv", "mcu_pos_z", STEP_UM)
    plain = load_run(DATASETS / "paper_cycle.csv", temps=["T1", "T2"])
    scaled = load_run(tmp_path / "steps.csv", temps=["T1", "T2"], error="mcu_pos_z*2.5")
    np.testing.assert_allclose(scaled.error, plain.error, rtol=1e-12, atol=1e-12)
    assert scaled.error_name == "mcu_pos_z*2.5"
    assert any("column 'mcu_pos_z' read ×2.5 as µm" in note for note in scaled.notes)
    assert length_unit("mcu_pos_z*2.5") == ("×2.5", 2.5)
    bare = load_run(tmp_path / "steps.csv", temps=["T1", "T2"], error="mcu_pos_z")
    np.testing.assert_allclose(bare.error * STEP_UM, plain.error, rtol=1e-12)


def test_logged_probe_checks_are_read_with_their_factor(tmp_path):
    frame = pd.read_csv(DATASETS / "repeat_warm.csv")
    frame["probe_um"] = frame["error_um"] + 0.5
    frame["probe_steps"] = frame["probe_um"] / STEP_UM
    frame.to_csv(tmp_path / "next.csv", index=False)
    fit = ["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--temps", "T1,T2", "--out", str(tmp_path / "m")]
    assert main([*fit, "--quiet"]) == 0
    replays = []
    for column in ("probe_um", "probe_steps*2.5"):
        target = tmp_path / f"{len(replays)}.json"
        probe = ["--probe-every", "1800", "--probe-column", column, "--json", str(target)]
        assert main(["replay", str(tmp_path / "m" / "model.json"), "--data", str(tmp_path / "next.csv"), *probe]) == 0
        replays.append(json.loads(target.read_text()))
    assert replays[0]["probes"]["applied"] > 0
    assert [c["reading_um"] for c in replays[1]["probes"]["checks"]] == pytest.approx(
        [c["reading_um"] for c in replays[0]["probes"]["checks"]], rel=1e-12
    )


def test_the_plausible_range_applies_to_the_scaled_reading_whatever_the_sign_of_the_factor(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame["gauge"] = frame.pop("error_um") / -INCH_UM
    frame.loc[7, "gauge"] = 5.0  # 5 in: -127 mm, beyond a --range-error of 1e5 µm
    frame.to_csv(tmp_path / "wild.csv", index=False)
    fit = ["fit", "--data", str(tmp_path / "wild.csv"), "--temps", "T1,T2", "--error", "gauge*-25400"]
    assert main([*fit, "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert not (tmp_path / "o").exists()
    frame.loc[7, "gauge"] = frame.loc[6, "gauge"]
    frame.to_csv(tmp_path / "tame.csv", index=False)
    fit[2] = str(tmp_path / "tame.csv")
    assert main([*fit, "--out", str(tmp_path / "o"), "--quiet"]) == 0


@pytest.mark.parametrize(
    "columns, spec, says",
    [
        ({"z": 1.0}, "z*0", "the factor 0 must be a finite number other than 0"),
        ({"z": 1.0}, "z*1e999", "the factor inf must be a finite number other than 0"),
        ({"z": 1.0}, "zz*2.5", "column 'zz' not found; the columns are: time_s, T1, z"),
        ({"z_mm": 1.0}, "z_mm*1000", "column 'z_mm' is in mm by its name and read as µm without a factor"),
    ],
)
def test_a_factor_that_cannot_be_applied_is_refused_in_one_line(tmp_path, capsys, columns, spec, says):
    frame = pd.DataFrame({"time_s": np.arange(60) * 15.0, "T1": 20 + np.linspace(0, 3, 60)})
    for name, scale in columns.items():
        frame[name] = scale * np.sin(np.arange(60) / 9.0)
    frame.to_csv(tmp_path / "run.csv", index=False)
    code = main(
        ["fit", "--data", str(tmp_path / "run.csv"), "--temps", "T1", "--error", spec, "--out", str(tmp_path / "o")]
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and not (tmp_path / "o").exists()
    assert says in err and len(err.splitlines()) == 1


def test_a_factor_on_a_column_whose_row_of_units_gives_a_length_is_refused(tmp_path):
    lines = ["time_s,T1,z", "s,°C,mm"] + [f"{15 * k},{20 + 0.05 * k},{0.001 * k}" for k in range(40)]
    (tmp_path / "units.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(InputError, match="column 'z' is given a unit of length by the row of units"):
        load_run(tmp_path / "units.csv", temps=["T1"], error="z*1000")
    np.testing.assert_allclose(load_run(tmp_path / "units.csv", temps=["T1"], error="z").error[1], 1.0)


def test_a_model_file_whose_error_factor_is_zero_is_refused(tmp_path):
    assert main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), "--out", str(tmp_path / "m"), "--quiet"]) == 0
    document = json.loads((tmp_path / "m" / "model.json").read_text())
    document["error"] = "error_um*0"
    (tmp_path / "bad.json").write_text(json.dumps(document))
    with pytest.raises(InputError, match="its factor must be a finite number other than 0"):
        ModelFile.load(tmp_path / "bad.json")


def test_an_error_whose_every_reading_is_beyond_the_plausible_range_is_refused_when_resampled(tmp_path, capsys):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame["mcu_pos_z"] = frame.pop("error_um") / STEP_UM - 89869.0  # a printer's absolute position, in steps
    frame.to_csv(tmp_path / "steps.csv", index=False)
    period = float(np.diff(frame["time_s"])[0])
    fit = ["fit", "--data", str(tmp_path / "steps.csv"), "--temps", "T1,T2", "--error", "mcu_pos_z*2.5"]
    code = main([*fit, "--resample", f"{period:g}", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and not (tmp_path / "o").exists() and len(err.splitlines()) == 1
    first = frame["mcu_pos_z"].iloc[0] * STEP_UM
    assert f"every reading is beyond the plausible ±100000 µm (row 1: {first:g} µm)" in err
    spread = np.ptp(frame["mcu_pos_z"].to_numpy() * STEP_UM)  # the drift, within any plausible range
    assert f"while they span only {spread:.4g} µm: a position logged from the machine's zero" in err
    assert "less the run's first (the drift since the start) with --error 'mcu_pos_z*2.5-start'" in err
    wild = frame.assign(mcu_pos_z=frame["mcu_pos_z"] * 1e4)  # readings that spread beyond the range too
    wild.to_csv(tmp_path / "wild.csv", index=False)
    wild_fit = [
        *fit[:2],
        str(tmp_path / "wild.csv"),
        *fit[3:],
        "--resample",
        f"{period:g}",
        "--out",
        str(tmp_path / "o"),
    ]
    assert main(wild_fit) == 2
    err = capsys.readouterr().err.strip()
    assert "or name the thermal error's column" in err and "machine's zero" not in err
    marked = frame.assign(mcu_pos_z=frame["mcu_pos_z"] * 0 + 3.9e37)  # a marker, not a position: no drift at all
    marked.to_csv(tmp_path / "wild.csv", index=False)
    assert main(wild_fit) == 2
    err = capsys.readouterr().err.strip()
    assert "or name the thermal error's column" in err and "machine's zero" not in err
    assert (
        main([*fit, "--resample", f"{period:g}", "--range-error", "1e6", "--out", str(tmp_path / "o"), "--quiet"]) == 0
    )
