import shutil
from pathlib import Path

import numpy as np
import pytest

from groupfit.data import load_run
from groupfit.grouping import Constraints
from groupfit.models.grouped import GroupedRegressor
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact
from groupfit.sweep.config import read_study
from groupfit.sweep.runs import execute_run

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets" / "synthetic_cycle.csv"


def study_of(tmp_path, grid, ga="", data=DATA):
    config = tmp_path / "study.toml"
    config.write_text(f'[data]\npath = "{Path(data).as_posix()}"\n[grid]\n{grid}\n[ga]\n{ga}\n', encoding="utf-8")
    return read_study(config)


@pytest.fixture(scope="module")
def cycle():
    run = load_run(DATA, temps=["T1", "T2", "T3", "T4"])
    return run.temps, run.error


def test_ga_run_equals_a_direct_grouped_regressor_fit(tmp_path, cycle):
    X, y = cycle
    study = study_of(
        tmp_path,
        'p = [2, 3]\nsearch = "ga"\nobjective = ["sae", "sse"]',
        "seed = [4]\nmax_generations = [40]\npopulation_size = [30]",
    )
    assert len(study.runs) == 4
    for run in study.runs:
        result = execute_run(run.spec, run.path)
        assert result["status"] == "done", result["error"]
        model = run.spec["model"]
        direct = GroupedRegressor(
            p=model["p"],
            objective=model["objective"],
            search="ga",
            population_size=30,
            max_generations=40,
            random_state=4,
            certify=False,
        ).fit(X, y)
        assert result["breaks"] == direct.breaks_
        assert result["objective"] == pytest.approx(direct.objective_value_, rel=1e-12)
        expected = np.column_stack([direct.intercept_, direct.coef_])
        np.testing.assert_allclose(result["coefficients"], expected, rtol=1e-10)
        assert result["search"]["seed"] == 4 and result["search"]["generations"] <= 40
        # the GA is compared with the certified optimum of the same problem
        assert result["exact_objective"] is not None and result["gap_percent"] >= -1e-9
        assert result["search_objective"] >= result["exact_objective"] * (1 - 1e-12)


def test_exact_rows_equal_solve_exact(tmp_path, cycle):
    X, y = cycle
    study = study_of(tmp_path, 'p = {start = 0, stop = 5}\nn = [0, 3]\nobjective = ["sae", "sse"]\nsearch = "exact"')
    assert len(study.runs) == 6 * 2 * 2
    optimum = {}
    for n in (0, 3):
        for objective in ("sae", "sse"):
            cost = SegmentCost(X, y, n=n, objective=objective)
            optimum[n, objective] = solve_exact(cost, Constraints.for_model(len(y), n, 3.0, 5), 5)
    for run in study.runs:
        result = execute_run(run.spec, run.path)
        model = run.spec["model"]
        reference = optimum[model["n"], model["objective"]]
        assert result["breaks"] == reference.breaks[model["p"]]
        assert result["search_objective"] == pytest.approx(reference.objective[model["p"]], rel=1e-9)
        assert result["objective"] == pytest.approx(reference.objective[model["p"]], rel=1e-6)
        assert result["gap_percent"] == 0.0


def test_a_run_that_cannot_be_done_is_failed_with_its_message(tmp_path):
    study = study_of(tmp_path, "p = [40]\nc = [3.0]")
    result = execute_run(study.runs[0].spec, study.runs[0].path)
    assert result["status"] == "failed"
    assert "p = 40 breaks do not fit N = 300" in result["error"]
    assert result["timings"]["total"] >= 0


def test_data_changed_after_reading_the_study_is_refused(tmp_path):
    copy = tmp_path / "run.csv"
    shutil.copy(DATA, copy)
    study = study_of(tmp_path, "p = [1]", data=copy)
    copy.write_text(copy.read_text().replace("21.63394", "21.63395"))
    result = execute_run(study.runs[0].spec, study.runs[0].path)
    assert result["status"] == "failed" and "has changed" in result["error"]


def test_content_sent_with_the_run_is_used_instead_of_the_path(tmp_path):
    study = study_of(tmp_path, "p = [2]")
    run = study.runs[0]
    from_path = execute_run(run.spec, run.path)
    from_bytes = execute_run(run.spec, str(tmp_path / "elsewhere" / "synthetic_cycle.csv"), DATA.read_bytes())
    assert from_bytes["status"] == "done"
    assert from_bytes["breaks"] == from_path["breaks"] and from_bytes["objective"] == from_path["objective"]


def test_selected_sensors_are_fitted(tmp_path, cycle):
    study = study_of(tmp_path, 'p = [1]\nsensors = [{select = "forward", k = 2}]')
    result = execute_run(study.runs[0].spec, study.runs[0].path)
    assert result["status"] == "done" and len(result["sensors"]) == 2
    run = load_run(DATA, temps=result["sensors"])
    direct = GroupedRegressor(p=1, search="exact").fit(run.temps, run.error)
    assert result["breaks"] == direct.breaks_
    assert result["objective"] == pytest.approx(direct.objective_value_, rel=1e-12)


def test_glitches_in_the_error_are_left_out_as_fit_leaves_them_unless_kept(tmp_path, cycle):
    import pandas as pd

    X, y = cycle
    frame = pd.read_csv(DATA)
    frame.loc[[120, 121], "error_um"] += 300.0  # two readings a measurement got wrong, back at the third
    glitched = tmp_path / "glitched.csv"
    frame.to_csv(glitched, index=False)
    kept = np.ones(len(y), dtype=bool)
    kept[[120, 121]] = False
    design = np.column_stack([np.ones(len(y)), X])
    for keep, rows in ((False, kept), (True, np.ones(len(y), dtype=bool))):
        folder = tmp_path / f"keep_{keep}"
        folder.mkdir()
        config = folder / "study.toml"
        config.write_text(
            f'[data]\npath = "{glitched.as_posix()}"\ntemps = ["T1", "T2", "T3", "T4"]\n'
            f'keep_glitches = {str(keep).lower()}\n[grid]\np = [0]\nobjective = "sse"\nsearch = "exact"\n',
            encoding="utf-8",
        )
        study = read_study(config)
        assert study.runs[0].spec["data"].get("glitches_left_out", False) is not keep
        assert any("glitch" in note for note in study.datasets[0].notes) is not keep
        result = execute_run(study.runs[0].spec, study.runs[0].path)
        assert result["status"] == "done", result["error"]
        expected = np.linalg.lstsq(design[rows], frame["error_um"].to_numpy()[rows], rcond=None)[0]
        np.testing.assert_allclose(np.ravel(result["coefficients"]), expected, rtol=1e-8, atol=1e-10)
    clean = study_of(tmp_path, "p = [0]")
    assert "glitches_left_out" not in clean.runs[0].spec["data"]  # a clean run keeps its hash
