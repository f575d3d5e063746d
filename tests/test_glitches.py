"""Glitches in the measured error: found where they were put and nowhere else, and left out as not measured."""

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run, load_runs
from groupfit.glitches import (
    MIN_MEASURED_SHARE,
    TEMPERATURE_RANGE_SHARE,
    WINDOW,
    error_glitches,
    temperatures_without_glitches,
)
from groupfit.model import ModelFile
from groupfit.model import model_file_problem as model_problem

ROOT = Path(__file__).resolve().parents[1]
DATASETS = ROOT / "datasets"
MEASURED = ROOT.parent / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
sys.path.insert(0, str(ROOT / "bench"))
import independent_machine as machine  # noqa: E402

TEMPS = "T1,T2,T3,T4"
COMMON = ["--temps", TEMPS, "--reference", "none", "--quiet", "--p", "0", "--ridge", "0", "--recalibrate", "none"]


def shipped_errors():
    for path in sorted(DATASETS.glob("*.csv")):
        frame = pd.read_csv(path)
        if "error_um" in frame:
            yield path.name, frame["error_um"].to_numpy(dtype=float)


@pytest.mark.parametrize("name, error", list(shipped_errors()), ids=lambda v: v if isinstance(v, str) else "")
def test_no_reading_of_a_shipped_run_is_a_glitch(name, error):
    assert error_glitches(error).size == 0
    # nor when the error is missing on every third row
    assert error_glitches(np.where(np.arange(len(error)) % 3 == 1, np.nan, error)).size == 0


def test_an_error_measured_on_few_rows_is_not_tested():
    # a probe cycle every second row: readings too far apart to tell a glitch from a change
    error = pd.read_csv(DATASETS / "paper_cycle.csv")["error_um"].to_numpy(dtype=float, copy=True)
    error[100] += 300.0
    assert error_glitches(error).tolist() == [100]
    half = np.where(np.arange(len(error)) % 2 == 0, error, np.nan)
    assert np.isfinite(half).sum() >= MIN_MEASURED_SHARE * len(error) and error_glitches(half).tolist() == [100]
    half[[0, 2]] = np.nan  # two readings fewer: just under half the rows measured
    assert np.isfinite(half).sum() < MIN_MEASURED_SHARE * len(error) and error_glitches(half).size == 0


def test_no_reading_of_the_independent_machines_runs_is_a_glitch():
    for seed in range(12):
        scenario = machine.random_spec(seed, "absolute").make()
        for run in (scenario.modelling, scenario.validation):
            assert error_glitches(run["error_um"].to_numpy(dtype=float)).size == 0, scenario.name


@pytest.mark.parametrize("length", [1, 2, WINDOW // 2])
def test_glitches_are_found_where_they_were_put_whatever_their_sign(length):
    error = pd.read_csv(DATASETS / "paper_cycle.csv")["error_um"].to_numpy(dtype=float)
    rng = np.random.default_rng(length)
    largest = int(np.argmax(np.abs(error[20:-20]))) + 20  # a logger that wrote 0 where the error is largest
    others = [s for s in np.arange(20, len(error) - 20, 40) if abs(s - largest) > 2 * WINDOW]
    starts = np.sort([largest, *rng.choice(others, 3, replace=False)])
    rows = np.concatenate([np.arange(s, s + length) for s in starts])
    glitched = error.copy()
    for start, jump in zip(starts[starts != largest], (300.0, -250.0, 40.0)):
        glitched[start : start + length] += jump
    glitched[largest : largest + length] = 0.0
    np.testing.assert_array_equal(error_glitches(glitched), rows)


def test_a_step_of_the_error_is_not_a_glitch_and_a_reading_beyond_its_one_sided_neighbours_at_an_end_is():
    error = pd.read_csv(DATASETS / "paper_cycle.csv")["error_um"].to_numpy(dtype=float)
    stepped = error + np.where(np.arange(len(error)) >= 200, 0.5 * np.ptp(error), 0.0)
    assert error_glitches(stepped).size == 0
    ends = error.copy()
    ends[0] += 300.0
    ends[-1] -= 300.0
    assert error_glitches(ends).tolist() == [0, len(error) - 1]
    started = error.copy()
    started[:2] = started[2] - 0.3 * np.ptp(error)  # a start off the rest, but by less than half the range
    assert error_glitches(started).size == 0


def test_a_quiet_run_of_repeated_readings_has_no_glitch():
    # a resolution of 1 µm: most departures from the running median are 0, the spread with them
    error = np.round(np.linspace(0.0, 20.0, 400) + 0.3 * np.sin(np.arange(400) / 3.0))
    assert error_glitches(error).size == 0


@pytest.fixture(scope="module")
def glitched(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("glitches")
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    rows = [100, 101, 300]
    dirty = frame.copy()
    dirty.loc[rows, "error_um"] = [312.0, 311.0, -250.0]
    dirty.to_csv(tmp / "dirty.csv", index=False)
    emptied = frame.copy()
    emptied.loc[rows, "error_um"] = np.nan
    emptied.to_csv(tmp / "emptied.csv", index=False)
    return tmp, rows, dirty


def fitted(tmp: Path, data: str, out: str, *extra: str) -> tuple[ModelFile, str]:
    """The model ``fit`` writes and its report."""
    report = tmp / f"{out}.txt"
    stdout, sys.stdout = sys.stdout, open(report, "w")
    try:
        code = main(["fit", "--data", str(tmp / data), "--out", str(tmp / out), *COMMON, *extra])
    finally:
        sys.stdout.close()
        sys.stdout = stdout
    assert code == 0
    return ModelFile.load(tmp / out / "model.json"), report.read_text()


def coefficients(model: ModelFile) -> np.ndarray:
    return model.coefficient_matrix()[0]


def test_fit_leaves_the_glitches_out_as_it_leaves_out_rows_not_measured(glitched):
    tmp, rows, dirty = glitched
    model, report = fitted(tmp, "dirty.csv", "dirty", "--json", str(tmp / "dirty.json"))
    reference, _ = fitted(tmp, "emptied.csv", "emptied")
    noted = [line.removeprefix("note").strip() for line in report.splitlines() if "leave their neighbours" in line]
    assert json.loads((tmp / "dirty.json").read_text())["training"]["data_notes"] == noted
    assert list(model.training["data_notes"]) == noted and "data_notes" not in reference.training
    np.testing.assert_allclose(coefficients(model), coefficients(reference), rtol=1e-12, atol=1e-12)
    note = next(line for line in report.splitlines() if "leave their neighbours" in line)
    assert "3 reading(s) of 'error_um'" in note and "--keep-glitches" in note
    assert all(f"row {r + 1}: " in note for r in rows)  # 1-based data rows


def test_keep_glitches_fits_on_them_as_least_squares_does(glitched, tmp_path):
    tmp, _, dirty = glitched
    model, report = fitted(tmp, "dirty.csv", "kept", "--keep-glitches")
    assert "leave their neighbours" not in report
    design = np.column_stack([np.ones(len(dirty)), dirty[TEMPS.split(",")].to_numpy(dtype=float)])
    least_squares = np.linalg.lstsq(design, dirty["error_um"].to_numpy(dtype=float), rcond=None)[0]
    np.testing.assert_allclose(coefficients(model), least_squares, rtol=1e-8, atol=1e-8)
    # the configuration's [data] keep_glitches does the same
    config = tmp_path / "run.toml"
    config.write_text(f'[data]\npath = "{tmp / "dirty.csv"}"\nkeep_glitches = true\n')
    stdout, sys.stdout = sys.stdout, open(tmp_path / "report.txt", "w")
    try:
        assert main(["fit", str(config), "--out", str(tmp_path / "cfg"), *COMMON]) == 0
    finally:
        sys.stdout.close()
        sys.stdout = stdout
    configured = ModelFile.load(tmp_path / "cfg" / "model.json")
    np.testing.assert_allclose(coefficients(configured), least_squares, rtol=1e-8, atol=1e-8)


def test_resampling_averages_without_the_glitches(glitched):
    tmp, _, _ = glitched
    model, report = fitted(tmp, "dirty.csv", "resampled", "--resample", "200")
    reference, _ = fitted(tmp, "emptied.csv", "resampled_emptied", "--resample", "200")
    assert "leave their neighbours" in report
    np.testing.assert_allclose(coefficients(model), coefficients(reference), rtol=1e-12, atol=1e-12)


@pytest.fixture(scope="module")
def clean_model(glitched) -> Path:
    """The model ``fit`` writes for the run with its glitches emptied."""
    tmp = glitched[0]
    model = tmp / "emptied" / "model.json"
    if not model.exists():
        fitted(tmp, "emptied.csv", "emptied")
    return model


def test_diagnose_reads_the_run_without_its_glitches(glitched, clean_model, capsys):
    tmp = glitched[0]
    capsys.readouterr()
    args = ["diagnose", str(clean_model), "--out"]
    dirty_run, emptied_run = ("--data", str(tmp / "dirty.csv")), ("--data", str(tmp / "emptied.csv"))
    validate = ("--validate", str(DATASETS / "repeat_timing.csv"))
    assert main([*args, str(tmp / "diag_dirty"), *dirty_run, *validate, "--json", "-"]) == 0
    dirty_out, dirty_report = capsys.readouterr()
    assert main([*args, str(tmp / "diag_emptied"), *emptied_run, *validate, "--json", "-"]) == 0
    emptied = json.loads(capsys.readouterr().out)
    dirty = json.loads(dirty_out[dirty_out.index("{") :])
    assert dirty["before"] == emptied["before"] and dirty["after"] == emptied["after"]
    assert dirty["validation_runs"] == emptied["validation_runs"]
    # a validation run's glitches are left out of its figures as well (the modelling run the same less its last
    # row: a run is not both the modelling and the validation run)
    figures = []
    modelling = tmp / "emptied_modelling.csv"
    pd.read_csv(tmp / "emptied.csv").iloc[:-1].to_csv(modelling, index=False)
    for validation in ("dirty", "emptied"):
        capsys.readouterr()
        out = str(tmp / f"diag_{validation}_validation")
        assert (
            main([*args, out, "--data", str(modelling), "--validate", str(tmp / f"{validation}.csv"), "--json", "-"])
            == 0
        )
        figures.append([{**run, "name": None} for run in json.loads(capsys.readouterr().out)["validation_runs"]])
    assert figures[0] == figures[1]
    assert "leave their neighbours" in dirty_report  # the report goes to stderr with --json -


def test_replay_scores_the_glitches_as_logged_and_gives_the_rms_without_them(glitched, clean_model, capsys):
    tmp, rows, _ = glitched
    capsys.readouterr()
    assert main(["replay", str(clean_model), "--data", str(tmp / "dirty.csv"), "--json", "-"]) == 0
    out, report = capsys.readouterr()
    data = json.loads(out)
    residual = np.array([np.nan if s["residual_um"] is None else s["residual_um"] for s in data["samples"]])
    assert data["rms_um"] == pytest.approx(np.sqrt(np.nanmean(residual**2)), rel=1e-9)  # the glitches counted
    assert data["glitch_rows"] == [r + 1 for r in rows]
    kept = np.delete(residual, rows)
    assert data["rms_without_glitches_um"] == pytest.approx(np.sqrt(np.nanmean(kept**2)), rel=1e-9)
    assert data["rms_without_glitches_um"] < data["rms_um"] / 5
    assert any("come back (rows 101, 102, 301)" in note for note in data["notes"])


def test_compare_scores_a_validation_run_without_its_glitches(glitched, capsys):
    tmp, _, _ = glitched
    rows = []
    for validation, flags in (("dirty", []), ("emptied", []), ("dirty", ["--keep-glitches"])):
        out = tmp / f"compare_{validation}{len(flags)}"
        args = ["compare", "--data", str(DATASETS / "repeat_timing.csv"), "--validate", str(tmp / f"{validation}.csv")]
        args += ["--pmax", "1", "--temps", TEMPS, "--quiet", "--out", str(out), "--json", "-", *flags]
        assert main(args) == 0
        result = json.loads(capsys.readouterr().out)
        rows.append([{**row, "run": None} for row in result["rows"] if row["run"] == validation])
    assert rows[0] and rows[0] == rows[1]
    assert all(kept["rms_um"] > 10 * left["rms_um"] for kept, left in zip(rows[2], rows[0]))


@pytest.mark.parametrize("notes", ["a line", [""], [3], ["a line", None]])
def test_a_model_file_whose_data_notes_are_not_lines_is_refused(clean_model, notes):
    model = json.loads(clean_model.read_text())
    model.setdefault("training", {})["data_notes"] = ["glitches left out"]
    assert model_problem(model) is None
    model["training"]["data_notes"] = notes
    assert "training.data_notes must be a list of lines" in model_problem(model)


def test_diagnose_keeps_its_own_runs_loading_notes(glitched, clean_model):
    tmp = glitched[0]
    for data, flags, expected in (("dirty.csv", [], True), ("dirty.csv", ["--keep-glitches"], False)):
        out = tmp / f"diag_notes{len(flags)}"
        args = ["diagnose", str(clean_model), "--data", str(tmp / data), "--out", str(out), "--recalibrate", "none"]
        stdout, sys.stdout = sys.stdout, open(tmp / "diag_notes.txt", "w")
        try:
            assert main([*args, *flags]) == 0
        finally:
            sys.stdout.close()
            sys.stdout = stdout
        written = next(out.glob("model_*.json"))
        notes = ModelFile.load(written).training.get("data_notes", [])
        assert any("leave their neighbours" in note for note in notes) == expected


# ------------------------------------------------------------------------- a sensor's glitch


def test_no_temperature_of_a_shipped_or_simulated_run_is_a_glitch():
    frames = [pd.read_csv(path) for path in sorted(DATASETS.glob("*.csv"))]
    for seed in range(12):
        scenario = machine.random_spec(seed, "absolute").make()
        frames += [scenario.modelling, scenario.validation]
    checked = 0
    for frame in frames:
        for column in [c for c in frame.columns if str(c).startswith("T")]:
            values = frame[column].to_numpy(dtype=float)
            assert error_glitches(values, range_share=TEMPERATURE_RANGE_SHARE).size == 0, column
            checked += 1
    assert checked > 200


@pytest.mark.measured
@pytest.mark.skipif(not MEASURED.exists(), reason="../shared/data absent (a fresh clone has no measured data)")
def test_the_short_bumps_of_a_measured_sensor_are_no_glitches():
    frame = pd.read_csv(MEASURED)  # t16_C rises by 2-3 K for a few samples, five times
    sensors = [f"t{k}_C" for k in range(1, 17)]
    _, _, note = temperatures_without_glitches(frame, sensors, frame[sensors].to_numpy(dtype=float), "measured")
    assert note is None


@pytest.fixture(scope="module")
def spiked(tmp_path_factory):
    """The FE modelling run with a DS18B20's 85 °C power-on reading in T4 at data row 251, and plainly."""
    tmp = tmp_path_factory.mktemp("spiked")
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    frame.to_csv(tmp / "clean.csv", index=False)
    frame.loc[250, "T4"] = 85.0
    frame.to_csv(tmp / "spiked.csv", index=False)
    return tmp, frame


@pytest.mark.parametrize("row", [0, -1], ids=["first row", "last row"])
def test_a_power_on_reading_in_the_first_or_last_row_is_held_at_its_one_neighbour(tmp_path, row):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    clean = load_run(frame, temps=TEMPS.split(","))
    frame.loc[frame.index[row], "T4"] = 85.0
    run = load_run(frame, temps=TEMPS.split(","), drop_glitches=True)
    expected = clean.temps.copy()
    expected[row, 3] = clean.temps[1 if row == 0 else -2, 3]
    np.testing.assert_allclose(run.temps, expected, rtol=0, atol=1e-12)
    assert any(f"('T4' row {len(frame) if row else 1}: 85 °C)" in note for note in run.notes)


def test_a_temperature_glitch_is_interpolated_from_its_neighbours_and_named(spiked):
    tmp, frame = spiked
    clean = load_run(tmp / "clean.csv", temps=TEMPS.split(","))
    run = load_run(tmp / "spiked.csv", temps=TEMPS.split(","), drop_glitches=True)
    expected = clean.temps.copy()
    expected[250, 3] = 0.5 * (clean.temps[249, 3] + clean.temps[251, 3])  # straight across its neighbours
    np.testing.assert_allclose(run.temps, expected, rtol=0, atol=1e-12)
    assert any(
        "1 temperature reading(s) leave their neighbours and come back ('T4' row 251: 85 °C)" in n for n in run.notes
    )
    kept = load_run(tmp / "spiked.csv", temps=TEMPS.split(","))
    assert kept.temps[250, 3] == 85.0 and not any("temperature reading" in n for n in kept.notes)


def test_fit_on_a_spiked_sensor_comes_near_the_clean_fit_and_keep_glitches_does_not(spiked):
    tmp, _ = spiked
    clean, _ = fitted(tmp, "clean.csv", "clean")
    cleaned, report = fitted(tmp, "spiked.csv", "cleaned")
    kept, _ = fitted(tmp, "spiked.csv", "kept", "--keep-glitches")
    assert "a sensor's glitch: interpolated from its neighbours" in report
    near = np.abs(coefficients(cleaned) - coefficients(clean)).max()
    far = np.abs(coefficients(kept) - coefficients(clean)).max()
    assert near < 0.05 * np.abs(coefficients(clean)).max() and far > 10 * near


def test_a_glitch_of_the_air_temperature_the_inputs_are_taken_against_is_interpolated_too(spiked):
    tmp, frame = spiked
    air = pd.read_csv(DATASETS / "paper_cycle.csv")
    air.loc[300, "T_amb"] = 85.0
    air.to_csv(tmp / "air.csv", index=False)
    run = load_run(tmp / "air.csv", temps=TEMPS.split(","), drop_glitches=True)
    plain = air["T_amb"].to_numpy(dtype=float)
    assert run.frame["T_amb"].iloc[300] == pytest.approx(0.5 * (plain[299] + plain[301]), abs=1e-12)
    np.testing.assert_array_equal(np.delete(run.frame["T_amb"].to_numpy(), 300), np.delete(plain, 300))
    assert any("('T_amb' row 301: 85 °C)" in note for note in run.notes)
    assert load_run(tmp / "air.csv", temps=TEMPS.split(",")).frame["T_amb"].iloc[300] == 85.0


def test_a_glitch_of_the_air_temperature_named_by_ambient_is_interpolated_whatever_its_name(spiked):
    tmp, _ = spiked
    air = pd.read_csv(DATASETS / "paper_cycle.csv").rename(columns={"T_amb": "T15"})  # the air logged as a sensor
    air.loc[300, "T15"] = 85.0
    air.to_csv(tmp / "t15.csv", index=False)
    plain = air["T15"].to_numpy(dtype=float)
    (named,) = load_runs(tmp / "t15.csv", temps=TEMPS.split(","), drop_glitches=True, ambient="T15")  # --ambient T15
    assert named.frame["T15"].iloc[300] == pytest.approx(0.5 * (plain[299] + plain[301]), abs=1e-12)
    assert any("('T15' row 301: 85 °C)" in note for note in named.notes)
    unnamed = load_run(tmp / "t15.csv", temps=TEMPS.split(","), drop_glitches=True)
    assert unnamed.frame["T15"].iloc[300] == 85.0  # no column named as the air's: T15 is no reference
