"""Memory on long, wide logs: a global model is one least-squares fit without the grouped search's table of segment
sums; a grouped model whose table would exceed the budget is refused before work starts (fit --p P), left out of
the candidates (fit's default, compare) with a note, and the advice given is taken."""

import json
import re

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.commands import common
from groupfit.fit_budget import smallest_thinning
from groupfit.models.grouped import GroupedRegressor
from groupfit.objective import SegmentCost, segment_table_bytes

N_ROWS = 600
BUDGET = 50e3  # bytes: the table of 600 rows × 3 inputs (about 76 kB) is over it, that of 300 rows is within


@pytest.fixture(scope="module")
def run_csv(tmp_path_factory):
    path = tmp_path_factory.mktemp("wide") / "run.csv"
    rng = np.random.default_rng(3)
    temps = 20 + np.cumsum(rng.normal(0, 0.05, (N_ROWS, 3)), axis=0)
    error = temps @ np.array([2.0, -1.0, 0.5]) + np.where(np.arange(N_ROWS) < 300, 0.0, 3.0)
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3"]).assign(error_um=error + rng.normal(0, 0.1, N_ROWS))
    frame.insert(0, "time_s", np.arange(N_ROWS) * 10.0)
    frame.to_csv(path, index=False)
    return path


@pytest.fixture
def small_budget(monkeypatch):
    monkeypatch.setattr(common, "EXACT_BUDGET_BYTES", BUDGET)


@pytest.mark.parametrize("objective", ["sse", "sae"])
def test_a_global_model_is_least_squares_without_a_table_of_segment_sums(monkeypatch, objective):
    rng = np.random.default_rng(0)
    X = rng.normal(size=(400, 4))
    y = X @ [1.0, 2.0, -1.0, 0.5] + 3.0 + rng.normal(size=400)

    def no_table(*args, **kwargs):
        raise AssertionError("a global model built the table of segment sums")

    monkeypatch.setattr("groupfit.models.grouped.SegmentCost", no_table)
    model = GroupedRegressor(p=0, objective=objective).fit(X, y)
    expected, *_ = np.linalg.lstsq(np.column_stack([np.ones(400), X]), y, rcond=None)
    np.testing.assert_allclose(np.r_[model.intercept_, model.coef_[0]], expected, rtol=1e-10)
    residual = y - np.column_stack([np.ones(400), X]) @ expected
    objective_value = np.sum(residual**2) if objective == "sse" else np.sum(np.abs(residual))
    assert model.objective_value_ == pytest.approx(objective_value, rel=1e-10)
    assert model.search_["search_objective"] == model.objective_value_ and model.search_["evaluations"] == 1


@pytest.mark.parametrize(("n_samples", "n_inputs"), [(50, 1), (700, 3), (2000, 12)])
def test_the_table_size_counted_is_the_table_built(n_samples, n_inputs):
    rng = np.random.default_rng(n_inputs)
    cost = SegmentCost(rng.normal(size=(n_samples, n_inputs)), rng.normal(size=n_samples), objective="sse")
    table = cost._gram_prefix.nbytes  # noqa: SLF001
    counted = segment_table_bytes(n_samples, n_inputs + 1)
    assert table <= counted <= 3 * table  # the table, and the block of products it is summed from


def test_fit_refuses_a_grouped_model_over_the_memory_budget_and_its_advice_is_taken(
    tmp_path, capsys, run_csv, small_budget
):
    out = tmp_path / "out"
    assert main(["fit", "--data", str(run_csv), "--p", "1", "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "table of segment sums" in err[0] and str(run_csv) in err[0], err
    assert not out.exists()
    resample = re.search(r"--resample (\S+)\)", err[0]).group(1)
    assert main(["fit", "--data", str(run_csv), "--p", "1", "--resample", resample, "--quiet", "--out", str(out)]) == 0
    assert json.loads((out / "model.json").read_text())["p"] == 1
    assert (
        main(["fit", "--data", str(run_csv), "--p", "1", "--no-budget", "--quiet", "--out", str(tmp_path / "b")]) == 0
    )


def test_fits_default_tries_only_a_global_model_when_grouped_ones_are_over_the_budget(
    tmp_path, capsys, run_csv, small_budget
):
    report = tmp_path / "fit.json"
    args = ["fit", "--data", str(run_csv), "--quiet", "--out", str(tmp_path / "out"), "--json", str(report)]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "only p = 0 was tried" in out and "table of segment sums" in out
    assert json.loads(report.read_text())["p"] == 0


def test_fits_default_within_the_budget_tries_grouped_models(tmp_path, capsys, run_csv):
    report = tmp_path / "fit.json"
    args = ["fit", "--data", str(run_csv), "--quiet", "--out", str(tmp_path / "out"), "--json", str(report)]
    assert main(args) == 0
    assert "only p = 0 was tried" not in capsys.readouterr().out


def test_compare_leaves_grouped_models_out_over_the_budget(tmp_path, capsys, run_csv, small_budget):
    report = tmp_path / "c.json"
    args = ["compare", "--data", str(run_csv), "--heat", "none", "--pmax", "2", "--quiet"]
    assert main([*args, "--out", str(tmp_path / "cmp"), "--json", str(report)]) == 0
    assert "grouped models left out (--no-budget compares them)" in capsys.readouterr().out
    rows = json.loads(report.read_text())["rows"]
    assert not [r for r in rows if r["model"] == "grouped" and r["p"] > 0]


@pytest.mark.parametrize("needed", [1, 2, 3, 5, 64, 100, 10**6])
def test_the_smallest_thinning_is_the_first_power_of_two_within_and_ends_at_its_bound(needed):
    step = smallest_thinning(lambda k: k >= needed, most=64)
    expected = next((k for k in (2, 4, 8, 16, 32) if k >= needed), 64)
    assert step == expected
