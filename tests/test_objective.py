import numpy as np
import pytest
from conftest import brute_force_rg
from hypothesis import given, settings
from hypothesis import strategies as st

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost, grouped_residuals, ldl_least_squares, packed_index, residual_sum


def packed_gram(A, y):
    Z = np.column_stack([A, y])
    G = Z.T @ Z
    rows, cols = np.tril_indices(Z.shape[1])
    return G[rows, cols][:, None]


def test_ldl_matches_lstsq_on_a_full_rank_problem():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(30, 4))
    y = rng.normal(size=30)
    coef, sse = ldl_least_squares(packed_gram(A, y))
    reference, residual, *_ = np.linalg.lstsq(A, y, rcond=None)
    np.testing.assert_allclose(coef[0], reference, rtol=1e-10)
    np.testing.assert_allclose(sse[0], residual[0], rtol=1e-10)


def test_ldl_on_a_rank_deficient_problem_gives_the_least_squares_residual():
    rng = np.random.default_rng(4)
    x = rng.normal(size=(25, 2))
    A = np.column_stack([np.ones(25), x, x[:, 0]])  # last column repeats the second
    y = rng.normal(size=25)
    coef, sse = ldl_least_squares(packed_gram(A, y))
    reference = np.linalg.lstsq(A, y, rcond=None)[0]
    assert np.all(np.isfinite(coef))
    np.testing.assert_allclose(A @ coef[0], A @ reference, atol=1e-10)
    np.testing.assert_allclose(sse[0], np.sum((y - A @ reference) ** 2), rtol=1e-10)


def test_packed_index_is_symmetric_and_covers_the_triangle():
    index = packed_index(4)
    assert np.array_equal(index, index.T)
    assert sorted(set(index.ravel())) == list(range(10))


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(0, 3),
    objective=st.sampled_from(["sae", "sse"]),
    fit_intercept=st.booleans(),
    n_breaks=st.integers(0, 3),
)
def test_segment_costs_add_up_to_the_papers_rg(seed, n, objective, fit_intercept, n_breaks):
    rng = np.random.default_rng(seed)
    N = 60
    X = rng.normal(size=(N, 2)) + 20.0
    y = rng.normal(size=N) * 3.0 + 5.0
    constraints = Constraints.for_model(N, n, 2.0, 2 + fit_intercept)
    candidates = np.arange(constraints.lowest_break, constraints.highest_break + 1)
    breaks = sorted(rng.choice(candidates, size=n_breaks, replace=False).tolist())
    if not constraints.is_feasible(breaks):
        breaks = [10, 25, 45][:n_breaks]
    cost = SegmentCost(X, y, n=n, objective=objective, fit_intercept=fit_intercept)
    expected = brute_force_rg(X, y, breaks, n, objective, fit_intercept)
    assert cost.total(breaks) == pytest.approx(expected, rel=1e-9, abs=1e-9)
    _, residuals = grouped_residuals(X, y, breaks, n=n, fit_intercept=fit_intercept)
    assert residual_sum(residuals, objective) == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_collinear_sensors_get_the_minimum_norm_split():
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.normal(size=50))
    X = np.column_stack([t, t, rng.normal(size=50)])  # two identical sensors
    y = 2.0 * t + 0.5 * X[:, 2] + 1.0
    coefs, residuals = grouped_residuals(X, y, [25], n=3, fit_intercept=True)
    for coef in coefs:
        assert np.all(np.isfinite(coef))
        assert coef[1] == pytest.approx(coef[2], rel=1e-8)  # weight shared equally
        assert coef[1] + coef[2] == pytest.approx(2.0, rel=1e-8)
    assert np.max(np.abs(residuals)) < 1e-9
    cost = SegmentCost(X, y, n=3, objective="sse")
    assert cost.total([25]) < 1e-12 * np.sum((y - y.mean()) ** 2)


def test_large_offsets_keep_their_digits():
    # temperatures around 1000 and an error offset of 1e4: standardisation keeps the sums exact enough
    rng = np.random.default_rng(6)
    X = 1000.0 + rng.normal(size=(400, 3)).cumsum(axis=0) * 0.1
    y = 1e4 + X @ [1.0, -2.0, 0.5] + rng.normal(size=400) * 0.01
    cost = SegmentCost(X, y, n=3, objective="sse")
    breaks = [100, 250]
    assert cost.total(breaks) == pytest.approx(brute_force_rg(X, y, breaks, 3, "sse", True), rel=1e-6)


def test_sae_costs_in_blocks_equal_the_direct_sums(monkeypatch):
    """Many candidate groups sharing a first row are scored a few at a time (bounded memory), exactly."""
    rng = np.random.default_rng(11)
    N = 400
    X = np.cumsum(rng.normal(size=(N, 2)), axis=0)
    y = X @ [1.5, -0.7] + rng.normal(size=N)
    cost = SegmentCost(X, y, n=0, objective="sae", fit_intercept=True)
    a = np.zeros(150, dtype=np.int64)
    b = np.arange(N - 149, N + 1)
    monkeypatch.setattr("groupfit.objective.SAE_BLOCK_ELEMENTS", 3 * N)  # three candidates at a time
    blocked = cost.pair_costs(a, b)
    A = np.column_stack([np.ones(N), X])
    direct = [np.sum(np.abs(y[:last] - A[:last] @ np.linalg.lstsq(A[:last], y[:last], rcond=None)[0])) for last in b]
    np.testing.assert_allclose(blocked, direct, rtol=1e-9)
