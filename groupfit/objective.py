"""The grouped-regression objective Rg and the cost of one soft group.

Rg (docs/methods.md §1, eq. 10/12) sums the residuals of every soft group and
subtracts the residuals of each overlap computed with the *earlier* group's
model, so every sample counts once, scored by the group that serves it. The
contribution of one soft group therefore depends only on the hard breaks
before and after it, ``a`` (0 for the first group) and ``b`` (N for the last):

* it is fitted by least squares on samples ``lo … b`` with
  ``lo = 1`` if ``a = 0`` else ``a − n + 1``;
* it is scored on the samples it serves, ``lo … b − n`` (``lo … N`` when
  ``b = N``), by the sum of absolute residuals (``sae``) or of squared
  residuals (``sse``).

:class:`SegmentCost` evaluates that contribution for many ``(a, b)`` pairs at
once. Like a ruptures cost it knows nothing about the search; the exact and
genetic searches in :mod:`groupfit.search` only call :meth:`SegmentCost.pair_costs`.

Least squares from prefix sums: with cumulative sums of ``zᵢzᵢᵀ`` for
``zᵢ = [aᵢ, yᵢ]`` (design row and target), the Gram matrix of any row range is a
difference of two sums. An LDLᵀ factorisation of that augmented Gram matrix
gives the coefficients and, as its last pivot, the residual sum of squares, in
O(M³) whatever the length of the range. Columns are centred (when there is an
intercept) and scaled first so that the sums keep their digits. Pivots below
``rank_rtol`` times their diagonal mark a column that depends on earlier ones;
its coefficient is set to zero, which leaves the fitted values (and so the
cost) those of any least-squares solution.
"""

from __future__ import annotations

import copy
from typing import Sequence

import numpy as np

from groupfit.grouping import served_ranges, soft_groups
from groupfit.models.ridge import penalty_diagonal, ridge_solve

OBJECTIVES = ("sae", "sse")
SAE_BLOCK_ELEMENTS = 2**25
"""Residuals the sae cost holds at once (rows × candidate groups sharing a first row): 256 MiB of float64."""
RANK_RTOL = 1e-12
"""Relative pivot tolerance on the standardised Gram matrix (≈ 1e-6 on singular values)."""
LSTSQ_RCOND = 1e-6
"""Singular-value cut-off, relative to the largest, for the final minimum-norm fits."""


def design_matrix(X: np.ndarray, *, fit_intercept: bool) -> np.ndarray:
    """The regression design: a leading column of ones when there is an intercept."""
    X = np.asarray(X, dtype=float)
    if fit_intercept:
        return np.column_stack([np.ones(len(X)), X])
    return X


class Standardiser:
    """Centre (with an intercept) and scale the inputs and the target.

    Residuals of the standardised problem equal the original residuals divided
    by ``y_scale``; the fitted values of every range are unchanged.
    """

    def __init__(self, X: np.ndarray, y: np.ndarray, *, fit_intercept: bool):
        X = np.asarray(X, dtype=float)
        y = np.asarray(y, dtype=float)
        if fit_intercept:
            self.x_shift = X.mean(axis=0)
            self.y_shift = float(y.mean())
            x_spread = X.std(axis=0)
            y_spread = float(y.std())
        else:
            self.x_shift = np.zeros(X.shape[1])
            self.y_shift = 0.0
            x_spread = np.sqrt(np.mean(X**2, axis=0))
            y_spread = float(np.sqrt(np.mean(y**2)))
        self.x_scale = np.where(x_spread > 0, x_spread, 1.0)
        self.y_scale = y_spread if y_spread > 0 else 1.0
        self.fit_intercept = fit_intercept

    def design(self, X: np.ndarray) -> np.ndarray:
        return design_matrix(
            (np.asarray(X, dtype=float) - self.x_shift) / self.x_scale, fit_intercept=self.fit_intercept
        )

    def target(self, y: np.ndarray) -> np.ndarray:
        return (np.asarray(y, dtype=float) - self.y_shift) / self.y_scale


def packed_index(m: int) -> np.ndarray:
    """``index[i, j]``: row of entry (i, j) of a symmetric m×m matrix in packed storage."""
    index = np.zeros((m, m), dtype=np.intp)
    rows, cols = np.tril_indices(m)
    index[rows, cols] = np.arange(len(rows))
    index[cols, rows] = index[rows, cols]
    return index


def ldl_least_squares(
    gram: np.ndarray, rank_rtol: float = RANK_RTOL, *, coefficients: bool = True
) -> tuple[np.ndarray | None, np.ndarray]:
    """Least squares from stacked augmented Gram matrices.

    A right-looking LDLᵀ elimination, run on all K matrices at once.

    Parameters
    ----------
    gram : ndarray, shape (m(m+1)/2, K)
        The lower triangle (in the order of :func:`packed_index`) of
        ``[[AᵀA, Aᵀy], [yᵀA, yᵀy]]`` for K row ranges, one entry per row so
        that every operation runs over a contiguous vector of K ranges.
        Overwritten.
    coefficients : bool
        Whether to solve for the coefficients (the residual sum needs none).

    Returns
    -------
    coef : ndarray, shape (K, M), or None
        A least-squares solution per range (zero for dependent columns).
    sse : ndarray, shape (K,)
        The residual sum of squares of that fit on its own range.
    """
    n_packed, K = gram.shape
    m = int(round((np.sqrt(8 * n_packed + 1) - 1) / 2))
    index = packed_index(m)
    floor = rank_rtol * np.maximum(gram[index[np.arange(m), np.arange(m)]], 0.0)
    multipliers: list[list[np.ndarray]] = []
    for j in range(m - 1):
        pivot = gram[index[j, j]]
        alive = pivot > floor[j]
        inverse = np.where(alive, 1.0 / np.where(alive, pivot, 1.0), 0.0)
        column = [gram[index[i, j]] * inverse for i in range(j + 1, m)]
        for i in range(j + 1, m):
            factor = column[i - j - 1]
            for k in range(j + 1, i + 1):
                gram[index[i, k]] -= factor * gram[index[k, j]]
        multipliers.append(column)
    sse = np.maximum(gram[index[m - 1, m - 1]], 0.0)
    if not coefficients:
        return None, sse
    n_coef = m - 1
    coef = np.zeros((n_coef, K))
    for k in range(n_coef - 1, -1, -1):
        column = multipliers[k]
        coef[k] = column[n_coef - k - 1]
        for i in range(k + 1, n_coef):
            coef[k] -= column[i - k - 1] * coef[i]
    return coef.T, sse


def min_norm_lstsq(A: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Minimum-norm least-squares coefficients, small singular values cut at LSTSQ_RCOND."""
    coef, *_ = np.linalg.lstsq(A, y, rcond=LSTSQ_RCOND)
    return coef


PREFIX_BLOCK = 64
"""Products of input pairs summed at a time while building :class:`SegmentCost`'s table."""


def segment_table_bytes(n_samples: int, n_coef: int) -> float:
    """Memory of :class:`SegmentCost`'s table of prefix sums (every product of two design columns or the
    target, at every sample), with the block of products it is built from."""
    pairs = (n_coef + 1) * (n_coef + 2) / 2
    return 8.0 * (pairs * (n_samples + 1) + 2 * min(PREFIX_BLOCK, pairs) * n_samples)


class SegmentCost:
    """Cost of one soft group given the hard breaks around it.

    Parameters
    ----------
    X : array-like, shape (N, k)
        Temperatures.
    y : array-like, shape (N,)
        Thermal error.
    n : int
        Soft offset (samples shared by neighbouring soft groups).
    objective : {"sae", "sse"}
        Sum of absolute or of squared residuals.
    fit_intercept : bool
        Whether each group has a constant term.
    """

    def __init__(self, X, y, *, n: int = 3, objective: str = "sae", fit_intercept: bool = True):
        if objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            X = X[:, None]
        y = np.asarray(y, dtype=float).ravel()
        if len(X) != len(y):
            raise ValueError(f"X has {len(X)} rows but y has {len(y)}")
        self.n = int(n)
        self.objective = objective
        self.fit_intercept = fit_intercept
        self.standardiser = Standardiser(X, y, fit_intercept=fit_intercept)
        self.design = self.standardiser.design(X)
        self.target = self.standardiser.target(y)
        self.n_samples, self.n_coef = self.design.shape
        augmented = np.column_stack([self.design, self.target])
        rows, cols = np.tril_indices(self.n_coef + 1)
        self._gram_prefix = np.zeros((len(rows), self.n_samples + 1))
        for start in range(0, len(rows), PREFIX_BLOCK):  # a block of products at a time: one table in memory
            block = slice(start, start + PREFIX_BLOCK)
            self._gram_prefix[block, 1:] = np.cumsum(augmented[:, rows[block]] * augmented[:, cols[block]], axis=0).T
        self.evaluations = 0

    def soft_group_first(self, a: np.ndarray) -> np.ndarray:
        """First sample (1-based) of the soft group that follows hard break ``a``."""
        a = np.asarray(a)
        return np.where(a == 0, 1, a - self.n + 1)

    def served_last(self, b: np.ndarray) -> np.ndarray:
        """Last sample (1-based) the group ending at hard break ``b`` is scored on."""
        b = np.asarray(b)
        return np.where(b == self.n_samples, b, b - self.n)

    def pair_costs(self, a: Sequence[int], b: Sequence[int]) -> np.ndarray:
        """Contribution to Rg of the soft group between hard breaks ``a`` and ``b``.

        ``a`` and ``b`` are equal-length integer arrays (``a = 0`` for the first
        group, ``b = N`` for the last); costs are in the units of y (µm or µm²).
        """
        a = np.asarray(a, dtype=np.int64).ravel()
        b = np.asarray(b, dtype=np.int64).ravel()
        if a.size == 0:
            return np.empty(0)
        self.evaluations += a.size
        lo = self.soft_group_first(a)
        coef, sse_fit = self.pair_fits(lo, b, coefficients=self.objective == "sae" or self.n > 0)
        if self.objective == "sse":
            cost = sse_fit - self._overlap_sse(b, coef)
            return np.maximum(cost, 0.0) * self.standardiser.y_scale**2
        return self._sae(lo, self.served_last(b), coef) * self.standardiser.y_scale

    def pair_fits(self, lo: np.ndarray, b: np.ndarray, *, coefficients: bool = True):
        """Least-squares fits of the soft groups on rows ``lo … b`` (1-based), standardised.

        Returns ``(coef, sse)`` as :func:`ldl_least_squares` does; no segment is counted in
        :attr:`evaluations`.
        """
        gram = np.take(self._gram_prefix, b, axis=1) - np.take(self._gram_prefix, lo - 1, axis=1)
        return ldl_least_squares(gram, coefficients=coefficients)

    def with_objective(self, objective: str) -> "SegmentCost":
        """The same data and groups scored by another objective (shares the prefix sums; own count)."""
        if objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
        twin = copy.copy(self)
        twin.objective = objective
        twin.evaluations = 0
        return twin

    def _overlap_sse(self, b: np.ndarray, coef: np.ndarray) -> np.ndarray:
        """Squared residuals of each fit on the n samples its successor serves."""
        if self.n == 0:
            return np.zeros(len(b))
        inner = b < self.n_samples
        rows = (b[:, None] - self.n + np.arange(self.n)[None, :]) * inner[:, None]
        fitted = np.einsum("knm,km->kn", self.design[rows], coef)
        residual = self.target[rows] - fitted
        return np.where(inner, np.sum(residual**2, axis=1), 0.0)

    def _sae(self, lo: np.ndarray, last: np.ndarray, coef: np.ndarray) -> np.ndarray:
        """Sum of absolute residuals on rows lo…last, one residual pass per distinct lo."""
        cost = np.empty(len(lo))
        order = np.argsort(lo, kind="stable")
        starts = np.flatnonzero(np.r_[True, np.diff(lo[order]) != 0])
        ends = np.r_[starts[1:], len(order)]
        for s, e in zip(starts, ends):
            shared = order[s:e]
            shared = shared[np.argsort(last[shared], kind="stable")]
            first = int(lo[shared[0]])
            width = max(1, SAE_BLOCK_ELEMENTS // max(1, int(last[shared[-1]]) - first + 1))
            for k in range(0, len(shared), width):
                members = shared[k : k + width]
                rows = slice(first - 1, int(last[members[-1]]))
                residual = np.abs(self.target[rows, None] - self.design[rows] @ coef[members].T)
                cumulative = np.cumsum(residual, axis=0)
                cost[members] = cumulative[last[members] - first, np.arange(len(members))]
        return cost

    def total(self, breaks: Sequence[int]) -> float:
        """Rg of a whole break vector, from the same segment costs the searches use."""
        edges = np.array([0, *map(int, breaks), self.n_samples])
        return float(self.pair_costs(edges[:-1], edges[1:]).sum())


def grouped_residuals(
    X: np.ndarray,
    y: np.ndarray,
    breaks: Sequence[int],
    *,
    n: int,
    fit_intercept: bool,
    ridge_alpha: float = 0.0,
) -> tuple[list[np.ndarray], np.ndarray]:
    """Fit every soft group directly (minimum-norm least squares) and return the residuals.

    With ``ridge_alpha > 0`` each group's slopes are shrunk by the penalty of
    :mod:`groupfit.models.ridge` (on the inputs scaled to unit spread, so on
    the standardised design: ``ridge_alpha`` times the group's rows).

    Returns
    -------
    coefs : list of ndarray
        One coefficient vector per soft group, intercept first when used, in
        the original units.
    residuals : ndarray, shape (N,)
        ``y − ŷ`` where each sample is predicted by the group that serves it.
    """
    X = np.asarray(X, dtype=float)
    y = np.asarray(y, dtype=float)
    n_samples = len(y)
    std = Standardiser(X, y, fit_intercept=fit_intercept)
    A = std.design(X)
    t = std.target(y)
    coefs = []
    residuals = np.empty(n_samples)
    for (first, last), (s_first, s_last) in zip(soft_groups(breaks, n_samples, n), served_ranges(breaks, n_samples, n)):
        if ridge_alpha > 0:
            unit_spreads = np.ones(X.shape[1])  # the standardised inputs
            penalty = penalty_diagonal(unit_spreads, ridge_alpha, last - first + 1, fit_intercept=fit_intercept)
            coef = ridge_solve(A[first - 1 : last], t[first - 1 : last], penalty)
        else:
            coef = min_norm_lstsq(A[first - 1 : last], t[first - 1 : last])
        residuals[s_first - 1 : s_last] = (t[s_first - 1 : s_last] - A[s_first - 1 : s_last] @ coef) * std.y_scale
        coefs.append(unstandardise(coef, std))
    return coefs, residuals


def unstandardise(coef: np.ndarray, std: Standardiser) -> np.ndarray:
    """Coefficients of the standardised problem in the original units (intercept first)."""
    if std.fit_intercept:
        slopes = coef[1:] * std.y_scale / std.x_scale
        intercept = std.y_shift + coef[0] * std.y_scale - slopes @ std.x_shift
        return np.r_[intercept, slopes]
    return coef * std.y_scale / std.x_scale


def residual_sum(residuals: np.ndarray, objective: str) -> float:
    """R for one objective: sum of |e| (sae) or of e² (sse)."""
    residuals = np.asarray(residuals, dtype=float)
    return float(np.sum(np.abs(residuals)) if objective == "sae" else np.sum(residuals**2))
