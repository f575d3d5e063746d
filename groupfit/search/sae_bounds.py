"""Lower bounds of a segment's ``sae`` cost from prefix sums of signed rows.

For any signs ``|s_i| ≤ 1`` and any block of rows B, ``Σ_B |r_i| ≥ |Σ_B s_i r_i|``,
and for a fit β, ``Σ_B s_i r_i = (Σ_B s_i y_i) − (Σ_B s_i a_i)·β``: a difference
of two prefix sums dotted with ``[1, −β]``, O(K·M) per block for K sign vectors.
Summing the best sign vector's term over the blocks of a partition of the
served rows bounds the segment's ``sae`` from below.

Two partitions are used. :meth:`SignBounds.lower` splits every served range
into halves: cheap enough for every segment. With the signs of a good
break vector's residuals it is within a few per cent of the cost when the
residuals are noise-like. :meth:`SignBounds.grid_lower` cuts the range at a
fixed grid of step g: tight when residuals keep their sign over runs longer
than g (smooth thermal drifts), O(N/g) blocks per segment, so it is applied to
the segments the cheap bound could not rule out.

Every bound is lowered by a worst-case rounding margin (cumulative sums of N
terms, then a dot product), so it stays below the cost as computed.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from groupfit.grouping import served_ranges
from groupfit.objective import SegmentCost

RELATIVE_SLACK = 1e-9
"""Bounds are lowered by this fraction, and U_p raised by it (costs summed in another order)."""
_EPS = np.finfo(float).eps


class SignBounds:
    """Lower bounds of ``sae`` costs of least-squares fits.

    Parameters
    ----------
    cost : SegmentCost
    signs : sequence of ndarray, shape (N,)
        Sign vectors (entries in [−1, 1]); all ones is added.
    """

    def __init__(self, cost: SegmentCost, signs: Sequence[np.ndarray]):
        rows = np.column_stack([cost.target, -cost.design])
        vectors = _distinct([np.ones(len(rows)), *signs])
        signed = np.stack([s[:, None] * rows for s in vectors], axis=1)
        self.prefix = np.concatenate([np.zeros((1, *signed.shape[1:])), np.cumsum(signed, axis=0)])
        # each edge's value is off by at most this much per unit of |w| (cumulative sum, then dot product)
        self._edge_error = 2.0 * (len(rows) + rows.shape[1] + 2) * _EPS * np.abs(rows).sum(axis=0)
        self.y_scale = cost.standardiser.y_scale
        self.n_signs = len(vectors)

    def lower(self, lo: np.ndarray, last: np.ndarray, coef: np.ndarray) -> np.ndarray:
        """A lower bound (units of y) of Σ|t_i − a_i·β| over rows ``lo … last`` (1-based) for each fit β."""
        w = _weights(coef)
        start = lo - 1
        edges = [start, (start + last) // 2, last]
        previous = None
        total = np.zeros(len(lo))
        for edge in edges:
            value = np.einsum("pkm,pm->pk", self.prefix[edge], w)
            if previous is not None:
                total += np.abs(value - previous).max(axis=1)
            previous = value
        return self._finish(total, w, 2 * len(edges))

    def grid_lower(self, lo: int, last: np.ndarray, coef: np.ndarray, step: int) -> np.ndarray:
        """Like :meth:`lower` for segments that share their first row ``lo``, blocks cut at multiples of ``step``."""
        w = _weights(coef)
        start = lo - 1
        grid = np.arange((start // step + 1) * step, int(last.max()) + 1, step)
        edges = np.r_[start, grid]
        values = np.einsum("jkm,pm->kjp", self.prefix[edges], w)  # (K, J, segments)
        blocks = np.abs(np.diff(values, axis=1)).max(axis=0)
        cumulative = np.vstack([np.zeros((1, len(last))), np.cumsum(blocks, axis=0)])
        index = np.searchsorted(edges, last, side="right") - 1  # the last edge at or before each segment's end
        columns = np.arange(len(last))
        tail = np.einsum("pkm,pm->pk", self.prefix[last], w) - values[:, index, columns].T
        total = cumulative[index, columns] + np.abs(tail).max(axis=1)
        return self._finish(total, w, 2 * (index + 2))

    def _finish(self, total: np.ndarray, w: np.ndarray, n_edges) -> np.ndarray:
        margin = n_edges * (np.abs(w) @ self._edge_error)
        return np.maximum(total * (1.0 - RELATIVE_SLACK) - margin, 0.0) * self.y_scale


def _weights(coef: np.ndarray) -> np.ndarray:
    return np.column_stack([np.ones(len(coef)), coef])


def _distinct(vectors: list[np.ndarray]) -> list[np.ndarray]:
    kept: list[np.ndarray] = []
    for vector in vectors:
        if not any(np.array_equal(vector, other) for other in kept):
            kept.append(vector)
    return kept


def served_signs(cost: SegmentCost, breaks: Sequence[int], soft: float = 0.0) -> np.ndarray:
    """Sign of each sample's residual under the groups of ``breaks`` (each scored by the group serving it)."""
    edges = np.array([0, *map(int, breaks), cost.n_samples])
    coef, _ = cost.pair_fits(cost.soft_group_first(edges[:-1]), edges[1:])
    signs = np.empty(cost.n_samples)
    for (first, last), beta in zip(served_ranges(list(breaks), cost.n_samples, cost.n), coef):
        rows = slice(first - 1, last)
        signs[rows] = cost.target[rows] - cost.design[rows] @ beta
    if soft:
        return np.clip(signs / (soft * np.median(np.abs(signs))), -1, 1)
    return np.sign(signs)
