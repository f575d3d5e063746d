"""Choosing how many inputs: the held-out errors from fold Gram matrices equal the direct refits, and forward
and lasso selection keep the smallest subset within MIN_GAIN of the least error along their whole path."""

import numpy as np
import pytest

from groupfit.heldout.selection import (
    MIN_GAIN,
    HeldOutErrors,
    cluster_representatives,
    correlation_clusters,
    forward_selection,
    lasso_selection,
    time_series_folds,
)


def cv_error(X: np.ndarray, y: np.ndarray, splits) -> float:
    """The held-out mean squared error by a least-squares refit (with intercept) on the samples of every fold."""
    A = np.column_stack([np.ones(len(X)), X])
    squared = sum(float(np.sum((y[test] - A[test] @ np.linalg.lstsq(A[train], y[train], rcond=None)[0]) ** 2))
                  for train, test in splits)  # fmt: skip
    return squared / sum(len(test) for _, test in splits)


def random_walks(n: int, k: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return 25 + np.cumsum(rng.normal(0, 0.1, (n, k)), axis=0)


@pytest.mark.parametrize("seed", range(5))
def test_held_out_errors_from_grams_equal_refits_on_the_samples(seed):
    X = random_walks(400, 6, seed)
    y = X @ np.random.default_rng(seed).normal(size=6) + np.random.default_rng(seed + 9).normal(0, 0.1, 400)
    splits = time_series_folds(400, 5)
    held_out = HeldOutErrors(X, y, splits)
    for columns in ([0], [2, 4], [5, 1, 3], list(range(6))):
        assert held_out(columns) == pytest.approx(cv_error(X[:, columns], y, splits), rel=1e-8)


def joint_pair(seed: int):
    """y needs a difference of two strongly (but not 0.98) correlated sensors: each alone helps little."""
    rng = np.random.default_rng(seed)
    n = 600
    base = random_walks(n, 5, seed)
    twin = base[:, 1] + np.cumsum(rng.normal(0, 0.03, n))  # r ≈ 0.95 with sensor 1
    X = np.column_stack([base, twin])
    y = 2.0 * X[:, 0] + 6.0 * (X[:, 5] - X[:, 1]) + rng.normal(0, 0.05, n)
    return X, y, time_series_folds(n, 5)


@pytest.mark.parametrize("seed", range(14))
def test_forward_keeps_the_smallest_subset_of_its_whole_path_within_min_gain_of_the_least(seed):
    X, y, splits = joint_pair(seed)
    pool = cluster_representatives(X, y, correlation_clusters(X, min_corr=0.98))
    path, chosen, errors = [], [], []
    while pool:  # the forward path by direct refits: the representatives, then the other members
        scores = [cv_error(X[:, [*chosen, c]], y, splits) for c in pool]
        best = int(np.argmin(scores))
        chosen.append(pool.pop(best))
        errors.append(scores[best])
        path.append(list(chosen))
        if not pool:
            pool = [c for c in range(X.shape[1]) if c not in chosen]
    expected = next(p for p, e in zip(path, errors) if e <= min(errors) * (1 + MIN_GAIN))
    selected = forward_selection(X, y, None, splits=splits)
    assert selected == expected
    assert {1, 5} <= set(selected)  # the pair that only helps together
    assert cv_error(X[:, selected], y, splits) < 0.2 * cv_error(X[:, selected[:1]], y, splits)


@pytest.mark.parametrize("seed", range(4))
def test_lasso_without_k_keeps_what_the_least_squares_refit_asks_for(seed):
    X, y, splits = joint_pair(seed)
    selected = lasso_selection(X, y, None, splits=splits)
    every = cv_error(X, y, splits)
    assert cv_error(X[:, selected], y, splits) <= every * (1 + MIN_GAIN) + 1e-12
