"""Pick k sensors out of many candidate temperature columns.

An FE model can write a temperature at every node, and a machine may carry
more sensors than a compensation model should use. Three ways to choose k:

``cluster``
    Hierarchical clustering of the candidates on the distance ``1 − |r|``
    (r the correlation between two columns; average linkage) into k
    clusters; from each the member most correlated with the error.
``forward``
    Candidates correlated more than ``cluster_corr`` are merged into one
    cluster first (they carry the same information), and one representative
    of each is kept. Then forward selection: add, one at a time, the
    representative that most lowers the cross-validated squared error of a
    linear model, with folds in time order (each fold is predicted from the
    samples before it, as in service).
``lasso``
    LassoCV on the standardised candidates (the same time-ordered folds);
    the k largest coefficients at the chosen penalty, topped up, if fewer are
    non-zero, in the order columns enter the lasso path.

Every method is deterministic. Given ``splits`` (held-out folds such as whole
operating conditions or whole runs) instead of the time-ordered folds, the
methods score on them; ``k=None`` then chooses the number of sensors too:
each takes the smallest k whose held-out error (least squares on the chosen
columns) is within :data:`MIN_GAIN` of the least along its path: ``forward``
over its whole forward path, ``lasso`` over the columns in the order they
enter the lasso path, ``cluster`` over k = 1 … all.
"""

from __future__ import annotations

import warnings
from typing import Sequence

import numpy as np

from groupfit.errors import InputError

SELECTION_METHODS = ("forward", "lasso", "cluster")
SELECTION_DEFAULTS = {"folds": 5, "cluster_corr": 0.98}
MIN_GAIN = 0.02
"""With k chosen automatically, a sensor is added while it lowers the held-out squared error by this share."""
"""Settings a selection may give: time-ordered CV folds; correlation above which ``forward`` merges columns."""


def select_sensors(
    X: np.ndarray,
    y: np.ndarray,
    names: Sequence[str],
    method: str,
    k: int | None,
    *,
    folds: int = 5,
    cluster_corr: float = 0.98,
    splits=None,
) -> list[str]:
    """Names of the k chosen columns of ``X``, best first.

    Parameters
    ----------
    X : ndarray, shape (N, m)
        Candidate temperatures in time order.
    y : ndarray, shape (N,)
        Thermal error.
    names : sequence of str
        Column names of X.
    method : {"forward", "lasso", "cluster"}
    k : int or None
        Sensors to pick (1 ≤ k ≤ m); None chooses k on the held-out folds.
    folds : int
        Time-ordered cross-validation folds (``forward`` and ``lasso``), when no ``splits`` are given.
    cluster_corr : float
        ``forward`` treats columns correlated more than this as one.
    splits : list of (train, test) index arrays, optional
        Held-out folds to score on instead of the time-ordered ones.
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float).ravel()
    names = list(names)
    if X.ndim != 2 or X.shape[1] != len(names):
        raise ValueError("X must be 2-D with one column per name")
    if k is not None and not 1 <= k <= len(names):
        raise InputError(f"cannot pick k = {k} sensors out of {len(names)} candidates")
    splits = splits if splits is not None else time_series_folds(len(y), folds)
    if method == "cluster":
        chosen = cluster_selection(X, y, k) if k is not None else auto_cluster_selection(X, y, splits)
    elif method == "forward":
        chosen = forward_selection(X, y, k, splits=splits, cluster_corr=cluster_corr)
    elif method == "lasso":
        chosen = lasso_selection(X, y, k, splits=splits)
    else:
        raise InputError(f"sensor selection {method!r}: choose one of {', '.join(SELECTION_METHODS)}")
    return [names[i] for i in chosen]


def correlation_distance(X: np.ndarray) -> np.ndarray:
    """``1 − |r|`` between every pair of columns, a condensed distance vector."""
    from scipy.spatial.distance import squareform

    if X.shape[1] == 1:
        return np.empty(0)
    corr = np.corrcoef(X, rowvar=False)
    distance = np.clip(1.0 - np.abs(corr), 0.0, None)
    np.fill_diagonal(distance, 0.0)
    return squareform((distance + distance.T) / 2, checks=False)


def correlation_clusters(X: np.ndarray, *, n_clusters: int | None = None, min_corr: float | None = None) -> np.ndarray:
    """Cluster label (1…) of each column: into ``n_clusters``, or merging above ``min_corr``."""
    from scipy.cluster.hierarchy import fcluster, linkage

    if X.shape[1] == 1:
        return np.ones(1, dtype=int)
    tree = linkage(correlation_distance(X), method="average")
    if n_clusters is not None:
        return fcluster(tree, t=n_clusters, criterion="maxclust")
    return fcluster(tree, t=1.0 - float(min_corr), criterion="distance")


def target_correlation(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """|r| between each column and the target (0 for a constant column)."""
    Xc = X - X.mean(axis=0)
    yc = y - y.mean()
    norms = np.linalg.norm(Xc, axis=0) * np.linalg.norm(yc)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.abs(Xc.T @ yc) / norms
    return np.where(norms > 0, r, 0.0)


def cluster_representatives(X: np.ndarray, y: np.ndarray, labels: np.ndarray) -> list[int]:
    """The column of each cluster most correlated with y, the strongest cluster first."""
    strength = target_correlation(X, y)
    best = {}
    for column, label in enumerate(labels):
        if label not in best or strength[column] > strength[best[label]]:
            best[label] = column
    return sorted(best.values(), key=lambda c: (-strength[c], c))


def cluster_selection(X: np.ndarray, y: np.ndarray, k: int) -> list[int]:
    """One column from each of k correlation clusters."""
    chosen = cluster_representatives(X, y, correlation_clusters(X, n_clusters=k))[:k]
    if len(chosen) < k:  # fewer clusters than asked (identical columns): top up by correlation
        strength = target_correlation(X, y)
        rest = [c for c in np.argsort(-strength, kind="stable") if c not in chosen]
        chosen += [int(c) for c in rest[: k - len(chosen)]]
    return chosen


def time_series_folds(n_samples: int, folds: int):
    """(train, test) index pairs, each test block after its training samples."""
    from sklearn.model_selection import TimeSeriesSplit

    folds = max(2, min(int(folds), n_samples // 4))
    return list(TimeSeriesSplit(n_splits=folds).split(np.arange(n_samples)))


def auto_cluster_selection(X: np.ndarray, y: np.ndarray, splits) -> list[int]:
    """Cluster selection with the smallest k whose held-out error is within MIN_GAIN of the best k's."""
    options = [cluster_selection(X, y, k) for k in range(1, X.shape[1] + 1)]
    held_out = HeldOutErrors(X, y, splits)
    return options[smallest_within([held_out(chosen) for chosen in options])]


class HeldOutErrors:
    """Mean squared held-out error, over the test folds of ``splits`` (index arrays), of the least-squares fit
    (with intercept) of any subset of the columns of X, from each fold's Gram matrices built once: a subset
    costs solves of its own size, not passes over the samples (a forward path over 64 inputs: seconds, not
    minutes)."""

    def __init__(self, X: np.ndarray, y: np.ndarray, splits):
        spread = X.std(axis=0)
        A = np.column_stack([np.ones(len(X)), (X - X.mean(axis=0)) / np.where(spread > 0, spread, 1.0)])
        target = y - y.mean()
        self.folds = []
        self.count = 0
        for train, test in splits:
            trained, tested = A[train], A[test]
            self.folds.append(
                (
                    trained.T @ trained,
                    trained.T @ target[train],
                    tested.T @ tested,
                    tested.T @ target[test],
                    float(target[test] @ target[test]),
                )
            )
            self.count += len(test)

    def __call__(self, columns: Sequence[int]) -> float:
        rows = np.r_[0, np.asarray(columns, dtype=int) + 1]
        squared = 0.0
        for gram, moment, test_gram, test_moment, test_square in self.folds:
            coef, *_ = np.linalg.lstsq(gram[np.ix_(rows, rows)], moment[rows], rcond=None)
            squared += test_square - 2.0 * coef @ test_moment[rows] + coef @ test_gram[np.ix_(rows, rows)] @ coef
        return max(squared, 0.0) / self.count


def smallest_within(errors: Sequence[float]) -> int:
    """Index of the first of ``errors`` (a path of growing subsets) within MIN_GAIN of the least."""
    errors = np.asarray(errors, dtype=float)
    return int(np.flatnonzero(errors <= errors.min() * (1.0 + MIN_GAIN))[0])


def forward_selection(X: np.ndarray, y: np.ndarray, k: int | None, *, splits, cluster_corr: float = 0.98) -> list[int]:
    """Greedy forward selection on cluster representatives by held-out error. With k None the path runs through
    every representative, then through the clusters' other members, and the smallest subset within MIN_GAIN of
    the path's least error is kept: a sensor that helps little can come before several that help much, and
    sensors correlated above ``cluster_corr`` can still differ by what the error follows (64 sensors of five
    lags fall into five clusters, whose representatives leave five times the error all 64 leave)."""
    pool = cluster_representatives(X, y, correlation_clusters(X, min_corr=cluster_corr))
    if k is not None and len(pool) < k:
        pool += [c for c in range(X.shape[1]) if c not in pool]
    held_out = HeldOutErrors(X, y, splits)
    chosen: list[int] = []
    path: list[float] = []
    while pool and (k is None or len(chosen) < k):
        errors = [held_out([*chosen, c]) for c in pool]
        best = int(np.argmin(errors))
        path.append(errors[best])
        chosen.append(pool.pop(best))
        if not pool and k is None:  # then the clusters' other members: their differences may carry the error
            pool = [c for c in range(X.shape[1]) if c not in chosen]
    return chosen if k is not None else chosen[: smallest_within(path) + 1]


def lasso_selection(X: np.ndarray, y: np.ndarray, k: int | None, *, splits) -> list[int]:
    """The k largest LassoCV coefficients (standardised columns), topped up by path entry order.

    With k None: the columns in the order they enter the lasso path, as many as :func:`smallest_within` keeps
    of the held-out errors of their least-squares refits (the columns non-zero at the cross-validated penalty
    are chosen for the lasso's shrunk fit, not for the least-squares model fitted on them).
    """
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.linear_model import LassoCV, lasso_path

    spread = X.std(axis=0)
    Z = (X - X.mean(axis=0)) / np.where(spread > 0, spread, 1.0)
    target = (y - y.mean()) / (y.std() or 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        lasso = LassoCV(cv=splits, max_iter=20_000, random_state=0).fit(Z, target)
        magnitude = np.abs(lasso.coef_)
        ranked = [int(c) for c in np.argsort(-magnitude, kind="stable") if magnitude[c] > 0]
        if k is not None and len(ranked) >= k:
            return ranked[:k]
        alphas, path, _ = lasso_path(Z, target, alphas=lasso.alphas_, max_iter=20_000)
    order = np.argsort(-alphas, kind="stable")
    active = np.abs(path[:, order]) > 0
    entry = np.where(active.any(axis=1), active.argmax(axis=1), active.shape[1])
    entered = [int(c) for c in np.lexsort((np.arange(len(entry)), entry))]
    if k is None:  # by entry into the path, as many as the least-squares refit's held-out error asks for
        held_out = HeldOutErrors(X, y, splits)
        return entered[: smallest_within([held_out(entered[: j + 1]) for j in range(len(entered))]) + 1]
    for c in entered:
        if len(ranked) == k:
            break
        if c not in ranked:
            ranked.append(c)
    return ranked
