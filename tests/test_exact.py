import numpy as np
import pytest
import ruptures as rpt
from conftest import brute_force_optimum
from hypothesis import given, settings
from hypothesis import strategies as st

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(0, 3),
    objective=st.sampled_from(["sae", "sse"]),
    fit_intercept=st.booleans(),
)
@pytest.mark.slow
def test_exact_solver_agrees_with_enumeration(seed, n, objective, fit_intercept):
    rng = np.random.default_rng(seed)
    N = 30
    X = rng.normal(size=(N, 1)).cumsum(axis=0)
    y = rng.normal(size=N) + np.where(np.arange(N) < N // 2, 1.0, -1.0) * X[:, 0]
    c = 1.5
    M = 1 + fit_intercept
    constraints = Constraints.for_model(N, n, c, M)
    result = solve_exact(SegmentCost(X, y, n=n, objective=objective, fit_intercept=fit_intercept), constraints, 3)
    for p in range(0, 4):
        breaks, best = brute_force_optimum(X, y, p, n, c, objective, fit_intercept)
        if breaks is None:
            assert p not in result.breaks
            continue
        assert result.objective[p] == pytest.approx(best, rel=1e-9, abs=1e-9)
        # ties are possible in principle; the objective must match and the breaks must reach it
        if result.breaks[p] != breaks:
            from conftest import brute_force_rg

            assert brute_force_rg(X, y, result.breaks[p], n, objective, fit_intercept) == pytest.approx(best, rel=1e-9)


def piecewise_linear_data(N, seed, n_features=4, n_regimes=5):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(N, n_features)).cumsum(axis=0) * 0.1
    regime = np.minimum(np.arange(N) * n_regimes // N, n_regimes - 1)
    beta = rng.normal(size=(n_regimes, n_features))
    y = np.einsum("nk,nk->n", X, beta[regime]) + rng.normal(size=N) * 0.2
    return X, y


@pytest.mark.parametrize("N, seed", [(120, 0), (150, 1), (200, 2)])
def test_exact_solver_matches_ruptures_dynp(N, seed):
    X, y = piecewise_linear_data(N, seed)
    p, h = 4, 16
    signal = np.column_stack([y, np.ones(N), X])
    ruptures_breaks = rpt.Dynp(model="linear", min_size=h, jump=1).fit(signal).predict(n_bkps=p)[:-1]
    cost_model = rpt.costs.CostLinear().fit(signal)
    edges = [0, *ruptures_breaks, N]
    ruptures_value = sum(cost_model.error(a, b) for a, b in zip(edges[:-1], edges[1:]))

    result = solve_exact(SegmentCost(X, y, n=0, objective="sse"), Constraints(N, 0, h), p)
    assert result.breaks[p] == ruptures_breaks
    assert result.objective[p] == pytest.approx(ruptures_value, rel=1e-8)


def test_one_pass_answers_every_p_and_rg_never_rises_with_p(lumped_run):
    X, y = lumped_run
    constraints = Constraints.for_model(len(y), 3, 3.0, 5)
    result = solve_exact(SegmentCost(X, y, n=3, objective="sae"), constraints, 6)
    values = [result.objective[p] for p in range(7)]
    assert all(later <= earlier + 1e-9 for earlier, later in zip(values, values[1:]))
    for p in range(7):
        assert len(result.breaks[p]) == p and constraints.is_feasible(result.breaks[p])
        single = solve_exact(SegmentCost(X, y, n=3, objective="sae"), constraints, p)
        assert single.objective[p] == pytest.approx(result.objective[p], rel=1e-12)


def test_infeasible_p_is_left_out():
    X, y = piecewise_linear_data(40, 3, n_features=1)
    result = solve_exact(SegmentCost(X, y, n=0, objective="sse"), Constraints(40, 0, 15), 5)
    assert sorted(result.breaks) == [0, 1]
