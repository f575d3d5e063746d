"""``groupfit compare`` on runs whose error is measured on some rows only (a probe cycle every few samples)."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.probe_intervals import hold_residual

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
TEMPS = ["T1", "T2", "T3", "T4"]


def with_sparse_error(source: Path, target: Path, every: int, offset: int) -> pd.DataFrame:
    """``source`` with its error kept on every ``every``-th row (from ``offset``), the other cells empty."""
    frame = pd.read_csv(source)
    frame.loc[frame.index % every != offset, "error_um"] = np.nan
    frame.to_csv(target, index=False)
    return frame


@pytest.fixture(scope="module")
def sparse(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("sparse")
    model = with_sparse_error(DATASETS / "paper_cycle.csv", tmp / "model_run.csv", 5, 1)
    following = with_sparse_error(DATASETS / "validation_speed.csv", tmp / "next_run.csv", 7, 3)
    common = ["--temps", ",".join(TEMPS), "--reference", "none", "--quiet"]
    compare = [
        "compare",
        "--data",
        str(tmp / "model_run.csv"),
        "--validate",
        str(tmp / "next_run.csv"),
        "--heat",
        "speed_rpm",
        "--probe-every",
        "30m",
        "--out",
        str(tmp / "cmp"),
        "--json",
        str(tmp / "compare.json"),
    ]
    assert main(compare + common) == 0
    fit = ["fit", "--data", str(tmp / "model_run.csv"), "--out", str(tmp / "fit"), "--json", str(tmp / "fit.json")]
    assert main(fit + common) == 0
    return {
        "compare": json.loads((tmp / "compare.json").read_text()),
        "fit": json.loads((tmp / "fit.json").read_text()),
        "model": model,
        "next": following,
        "figures": sorted(p.name for p in (tmp / "cmp").iterdir()),
    }


def least_squares_residuals(sparse) -> dict[str, np.ndarray]:
    """The global regression on the modelling run's measured rows (numpy), its residual on each run's measured rows."""
    model = sparse["model"].dropna(subset=["error_um"])
    design = np.column_stack([np.ones(len(model)), model[TEMPS].to_numpy()])
    coef = np.linalg.lstsq(design, model["error_um"].to_numpy(), rcond=None)[0]
    residuals = {}
    for name, frame in (("model_run", sparse["model"]), ("next_run", sparse["next"])):
        residuals[name] = frame["error_um"].to_numpy() - np.column_stack([np.ones(len(frame)), frame[TEMPS]]) @ coef
    return residuals


def test_compare_fits_the_global_regression_on_the_measured_rows_and_scores_each_run_on_its_own(sparse):
    result = sparse["compare"]
    # grouped models and AR(1) need the error on every row; fit's model (with its ridge penalty) beside the MLR
    assert {r["model"] for r in result["rows"]} == {"mlr", "fit"}
    assert any("measured on 107 of 532 rows" in note for note in result["notes"])
    assert result["ar1"] is None and result["exact_path"]["breaks"] == [[]]
    for name, residual in least_squares_residuals(sparse).items():
        row = next(r for r in result["rows"] if r["run"] == name and r["model"] == "mlr")
        measured = residual[np.isfinite(residual)]
        assert row["rms_um"] == pytest.approx(np.sqrt(np.mean(measured**2)), rel=1e-9)
        assert row["max_um"] == pytest.approx(np.max(np.abs(measured)), rel=1e-9)
    assert "compare_next_run.png" in sparse["figures"]


def test_compare_marks_the_model_and_the_figure_fit_gives_the_same_run(sparse):
    expected = sparse["compare"]["expected_next_run"]
    assert expected["fit_would_choose_p"] == 0
    penalty = expected["fit_would_choose_ridge"]
    assert penalty["alpha"] == sparse["fit"]["ridge_alpha"]
    assert penalty["expected_next_run_rms_um"] == pytest.approx(sparse["fit"]["expected_next_run_rms_um"], rel=1e-12)


def test_compare_checks_a_sparse_run_where_it_was_measured(sparse):
    table = sparse["compare"]["probe_intervals"]
    row = next(r for r in table["rows"] if r["run"] == "next_run")
    residual = least_squares_residuals(sparse)["next_run"]
    every = 18  # 30 min at 100 s
    held = residual.copy()
    due = list(range(every - 1, len(residual), every))
    for k, row_due in enumerate(due):  # each check on the first measured row before the next one is due
        end = due[k + 1] if k + 1 < len(due) else len(residual)
        measured = [i for i in range(row_due, end) if np.isfinite(residual[i])]
        if measured:
            check = measured[0]
            held[check + 1 :] = residual[check + 1 :] - residual[check]
    assert row["rms_um"][0] == pytest.approx(np.sqrt(np.nanmean(held**2)), rel=1e-9)


def test_a_check_due_without_a_reading_moves_to_the_next_reading_before_the_next_check():
    residual = np.array([1.0, np.nan, 4.0, np.nan, np.nan, 16.0, 22.0])
    # due after rows 1, 3 and 5 (every 2): row 1 → row 2; row 3 has no reading before row 5; row 5 stays
    np.testing.assert_array_equal(hold_residual(residual, 2), [1.0, np.nan, 4.0, np.nan, np.nan, 12.0, 6.0])


def test_a_complete_modelling_run_keeps_every_model_and_scores_a_sparse_next_run_on_its_readings(tmp_path):
    following = with_sparse_error(DATASETS / "validation_speed.csv", tmp_path / "next_run.csv", 7, 3)
    out = tmp_path / "c.json"
    args = ["compare", "--data", str(DATASETS / "paper_cycle.csv"), "--validate", str(tmp_path / "next_run.csv")]
    args += ["--temps", ",".join(TEMPS), "--reference", "none", "--heat", "speed_rpm", "--pmax", "2"]
    assert main([*args, "--out", str(tmp_path / "cmp"), "--json", str(out), "--quiet"]) == 0
    rows = [r for r in json.loads(out.read_text())["rows"] if r["run"] == "next_run"]
    models = {("mlr", 0), ("fit", 0), ("ar1", None), ("grouped", 1), ("grouped", 2)}
    assert {(r["model"], r["p"]) for r in rows} == models
    assert all(np.isfinite(r["rms_um"]) for r in rows)  # the AR(1) free run starts from the first reading
    model = pd.read_csv(DATASETS / "paper_cycle.csv")
    design = np.column_stack([np.ones(len(model)), model[TEMPS]])
    coef = np.linalg.lstsq(design, model["error_um"], rcond=None)[0]
    residual = following["error_um"] - np.column_stack([np.ones(len(following)), following[TEMPS]]) @ coef
    mlr = next(r for r in rows if r["model"] == "mlr")
    assert mlr["rms_um"] == pytest.approx(np.sqrt(np.nanmean(residual**2)), rel=1e-9)
