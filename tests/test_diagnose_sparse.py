"""Rows without a measured error: they carry the derived inputs' history and are neither fitted nor scored."""

import json

import numpy as np
import pytest

from groupfit.cli import main
from groupfit.fast_response import without_stage
from groupfit.features import lowpass
from groupfit.model import ModelFile
from groupfit.synthetic import simulate_lumped

TEMPS = ["T1", "T2", "T3", "T4"]
PERIOD = 100.0
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")  # no statistic of an empty or all-NaN slice


def ambient_run(seed, n_samples=900, phase_h=0.0):
    """Sensors explain the error except a 2 h lag of the ambient."""
    frame = simulate_lumped({"seed": seed, "n_samples": n_samples})
    hours = frame["time_s"].to_numpy() / 3600.0
    frame["T_amb"] = 20.0 + 2.0 * np.sin(2 * np.pi * (hours - phase_h) / 9.0) + 1.5 * (hours > 6.0)
    rng = np.random.default_rng(seed + 7)
    frame["error_um"] = (
        frame[TEMPS].to_numpy() @ [0.8, 0.5, 1.1, 2.0]
        - 80.0
        + 1.2 * lowpass(frame["T_amb"].to_numpy() - 20.0, 7200.0, PERIOD)
        + rng.normal(scale=0.05, size=len(frame))
    )
    return frame


def probed(frame, every=60, width=12):
    """The error measured only in short probe cycles: ``width`` samples out of every ``every``."""
    frame = frame.copy()
    rows = (np.arange(len(frame)) % every) >= width
    frame.loc[rows, "error_um"] = np.nan
    return frame


def fit_model(tmp_path, frame):
    path = tmp_path / "fit.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "model"
    args = ["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--p", "0", "--reference", "none"]
    assert main([*args, "--search", "exact", "--out", str(out)]) == 0
    return out / "model.json"


def test_sparse_error_rows_carry_the_history_of_the_effect(tmp_path, capsys):
    modelling, other = probed(ambient_run(0)), probed(ambient_run(1, phase_h=4.0), every=90)
    model_path = fit_model(tmp_path, modelling)
    data, validate = tmp_path / "data.csv", tmp_path / "validate.csv"
    modelling.to_csv(data, index=False)
    other.to_csv(validate, index=False)
    capsys.readouterr()
    args = ["diagnose", str(model_path), "--data", str(data), "--validate", str(validate)]
    assert main([*args, "--out", str(tmp_path / "d"), "--json", str(tmp_path / "d.json")]) == 0
    result = json.loads((tmp_path / "d.json").read_text())
    assert result["added"][0]["column"] == "T_amb" and result["added"][0]["transform"] == "lowpass"
    assert any("measured on 180 of 900 rows" in note for note in result["notes"])
    assert result["improved"] is True
    assert result["after"]["validate"]["rms_um"] < 0.4 * result["before"]["validate"]["rms_um"]

    # the augmented model: least squares on the measured rows, its input computed over every row
    augmented = ModelFile.load(tmp_path / "d" / "model_augmented.json")
    feature = augmented.derived_inputs[0]
    full = modelling.copy()
    derived = feature.compute(full["T_amb"].to_numpy(), PERIOD)
    rows = full["error_um"].notna().to_numpy()
    A = np.column_stack([np.ones(len(full)), full[TEMPS], derived])[rows]
    expected = np.linalg.lstsq(A, full["error_um"].to_numpy()[rows], rcond=None)[0]
    np.testing.assert_allclose(augmented.coefficients[0], expected, rtol=1e-6, atol=1e-8)
    # ... which is not what the measured rows alone, run together, would give
    alone = feature.compute(full["T_amb"].to_numpy()[rows], PERIOD)
    assert np.max(np.abs(alone - derived[rows])) > 0.1

    # before/after are the error on the measured rows of each run, through the run-time rule
    given = without_stage(ModelFile.load(model_path))  # the model, without the stage fitted for probe checks
    validate_rows = other["error_um"].notna().to_numpy()
    residual = other["error_um"].to_numpy() - given.predict(other[TEMPS].to_numpy())
    assert result["before"]["validate"]["rms_um"] == pytest.approx(np.sqrt(np.mean(residual[validate_rows] ** 2)))


def test_fit_of_a_global_model_uses_the_measured_rows(tmp_path, capsys):
    frame = probed(ambient_run(3))
    capsys.readouterr()
    model = without_stage(ModelFile.load(fit_model(tmp_path, frame)))  # the model, without a stage for checks
    assert "the error is measured on 180 of 900 rows" in capsys.readouterr().out
    rows = frame["error_um"].notna().to_numpy()
    A = np.column_stack([np.ones(rows.sum()), frame.loc[rows, TEMPS]])
    expected = np.linalg.lstsq(A, frame.loc[rows, "error_um"], rcond=None)[0]
    np.testing.assert_allclose(model.coefficients[0], expected, rtol=1e-8, atol=1e-10)
    assert model.n_samples == 180
    path = tmp_path / "probed.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "grouped"
    assert main(["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--p", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "row 13, column 'error_um' is empty (720 rows" in err[0] and "--p 0" in err[0]
    assert not out.exists()


def test_what_an_empty_error_cannot_be_used_for_is_refused_in_one_line(tmp_path, capsys):
    frame = ambient_run(2, n_samples=400)
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    grouped = tmp_path / "grouped"
    args = ["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--p", "1", "--reference", "none"]
    assert main([*args, "--search", "exact", "--out", str(grouped), "--quiet"]) == 0
    global_model = fit_model(tmp_path, frame)
    cases = {
        "gaps": (probed(frame), grouped / "model.json", "a grouped model's residual needs the error on every row"),
        "empty": (frame.assign(error_um=np.nan), global_model, "is empty on every row"),
        "infinite": (
            frame.assign(error_um=np.where(frame.index == 5, np.inf, frame["error_um"])),
            global_model,
            "row 6",
        ),
    }
    for name, (data, model, message) in cases.items():
        csv = tmp_path / f"{name}.csv"
        data.to_csv(csv, index=False)
        capsys.readouterr()
        out = tmp_path / f"out-{name}"
        assert main(["diagnose", str(model), "--data", str(csv), "--out", str(out)]) == 2, name
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0] and csv.name in err[0], (name, err)
        assert not out.exists()
