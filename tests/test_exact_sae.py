"""The bounded exact search for sae against enumeration, against costing every segment, and in `fit`."""

from pathlib import Path

import numpy as np
import pytest
from conftest import brute_force_optimum, brute_force_rg

from groupfit.cli import main
from groupfit.grouping import Constraints
from groupfit.models.grouped import GroupedRegressor
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact
from groupfit.search.sae_bounds import SignBounds, served_signs


def two_regimes(seed, N=28, n_features=1):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(N, n_features)).cumsum(axis=0)
    slope = np.where(np.arange(N) < N // 2, 1.0, -1.0)
    return X, rng.normal(size=N) + slope * X[:, 0]


def piecewise_run(N, seed, n_features=4, n_regimes=5, noise=0.2):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(N, n_features)).cumsum(axis=0) * 0.1
    regime = np.minimum(np.arange(N) * n_regimes // N, n_regimes - 1)
    beta = rng.normal(size=(n_regimes, n_features))
    return X, np.einsum("nk,nk->n", X, beta[regime]) + rng.normal(size=N) * noise


@pytest.mark.parametrize(
    "seed, n, fit_intercept, every_p",
    [(1, 0, True, True), (3, 0, True, True), (5, 2, True, True), (7, 1, False, True), (11, 3, True, False)],
)
def test_bounded_sae_equals_enumeration(seed, n, fit_intercept, every_p):
    X, y = two_regimes(seed)
    c, pmax = 1.5, 3
    constraints = Constraints.for_model(len(y), n, c, 1 + fit_intercept)
    cost = SegmentCost(X, y, n=n, objective="sae", fit_intercept=fit_intercept)
    result = solve_exact(cost, constraints, pmax, every_p=every_p)
    assert result.pruning["segments"] > 0
    for p in range(pmax + 1) if every_p else [pmax]:
        breaks, best = brute_force_optimum(X, y, p, n, c, "sae", fit_intercept)
        assert result.objective[p] == pytest.approx(best, rel=1e-9, abs=1e-9)
        assert brute_force_rg(X, y, result.breaks[p], n, "sae", fit_intercept) == pytest.approx(best, rel=1e-9)
    if not every_p:
        assert sorted(result.objective) == [pmax]


@pytest.mark.parametrize("data", ["piecewise", "lumped"])
def test_bounded_sae_equals_costing_every_segment(data, lumped_run):
    X, y = piecewise_run(400, 4) if data == "piecewise" else lumped_run
    constraints = Constraints.for_model(len(y), 3, 3.0, X.shape[1] + 1)
    reference = solve_exact(SegmentCost(X, y, n=3, objective="sae"), constraints, 5, method="all-pairs")
    bounded = solve_exact(SegmentCost(X, y, n=3, objective="sae"), constraints, 5)
    assert bounded.breaks == reference.breaks
    for p, value in reference.objective.items():
        assert bounded.objective[p] == pytest.approx(value, rel=1e-12)
    assert bounded.pruning["costed"] + bounded.bounded == bounded.pruning["segments"] == reference.evaluations


def test_incumbents_tighten_but_never_change_the_optimum():
    X, y = piecewise_run(300, 5)
    constraints = Constraints.for_model(300, 3, 3.0, 5)
    plain = solve_exact(SegmentCost(X, y, n=3, objective="sae"), constraints, 4, every_p=False)
    poor = [30, 60, 90, 120]  # feasible, far from the optimum
    for given in ({4: poor}, {4: [5, 6, 7, 8]}, {4: plain.breaks[4]}, {2: poor}):
        result = solve_exact(SegmentCost(X, y, n=3, objective="sae"), constraints, 4, every_p=False, incumbents=given)
        assert result.breaks[4] == plain.breaks[4]
        assert result.objective[4] == pytest.approx(plain.objective[4], rel=1e-12)


def test_bounds_stay_below_costs_and_a_grid_of_single_rows_is_the_cost():
    rng = np.random.default_rng(2)
    N = 120
    base = rng.normal(size=N).cumsum()
    X = np.column_stack([base, base + rng.normal(size=N) * 1e-4, rng.normal(size=N)]) * 1e3  # collinear, large
    y = 3.0 * X[:, 2] - X[:, 0] + np.where(np.arange(N) < 60, 0.0, 40.0) + rng.normal(size=N)
    cost = SegmentCost(X, y, n=2, objective="sae")
    bounds = SignBounds(cost, [served_signs(cost, [60]), np.sign(rng.normal(size=N))])
    for a in [0, 10, 57]:
        b = np.arange(a + 8, N + 1)
        lo = cost.soft_group_first(np.full(len(b), a))
        coef, _ = cost.pair_fits(lo, b)
        last = cost.served_last(b)
        exact = cost.pair_costs(np.full(len(b), a), b)
        assert np.all(bounds.lower(lo, last, coef) <= exact)
        for step in (4, 16):
            assert np.all(bounds.grid_lower(int(lo[0]), last, coef, step) <= exact)
        single_rows = bounds.grid_lower(int(lo[0]), last, coef, 1)  # the cost less its rounding margin
        assert np.all(single_rows <= exact) and np.all(single_rows >= exact * (1 - 1e-4))


def test_clear_regimes_leave_few_segments_to_cost():
    X, y = piecewise_run(800, 0)
    result = solve_exact(SegmentCost(X, y, n=0, objective="sae"), Constraints(800, 0, 16), 4)
    assert np.abs(np.subtract(result.breaks[4], [160, 320, 480, 640])).max() < 8
    assert result.evaluations < 0.01 * result.pruning["segments"]


def test_fit_certifies_the_ga_on_sae_or_says_why_not():
    X, y = piecewise_run(700, 1, n_features=2)  # 245 000 segments: over the automatic limit for sae
    settings = dict(p=2, n=3, c=3.0, objective="sae", random_state=0, population_size=20, max_generations=15)
    skipped = GroupedRegressor(**settings).fit(X, y).search_
    assert "exact_objective" not in skipped and "of an automatic check" in skipped["exact_skipped"]
    certified = GroupedRegressor(**settings, certify=True).fit(X, y).search_
    reference = solve_exact(SegmentCost(X, y, n=3, objective="sae"), Constraints.for_model(700, 3, 3.0, 3), 2)
    assert certified["exact_objective"] == pytest.approx(reference.objective[2], rel=1e-12)
    assert certified["gap_percent"] >= -1e-9 and certified["exact_seconds"] > 0


def test_fit_prints_why_it_did_not_certify(tmp_path, capsys):
    data = Path(__file__).resolve().parents[1] / "datasets" / "synthetic_cycle.csv"
    argv = ["fit", "--data", str(data), "--temps", "T1,T2,T3,T4", "--out", str(tmp_path / "out"), "--quiet"]
    status = main([*argv, "--p", "2", "--certify", "no"])
    assert status == 0 and "not checked against the exact optimum: the check is turned off" in capsys.readouterr().out
