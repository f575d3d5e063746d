"""Exact break-point search by dynamic programming.

Rg is a sum of terms that each depend on two consecutive hard breaks (see
:mod:`groupfit.objective`), so the best break vector with p breaks is a
shortest path through break positions: ``F[k][b]``, the least cost of k groups
whose last one ends at sample b, obeys ``F[k][b] = min_a F[k−1][a] + cost(a, b)``.
Every feasible ``(a, b)`` pair is costed once and serves every k, so one pass
answers every p up to ``pmax`` (the segment-neighbourhood method; Auger &
Lawrence 1989, Bai & Perron 2003). Time O(pmax·N²) plus the N²/2 segment costs;
memory O(pmax·N).
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field

import numpy as np

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.base import SearchResult

CERTIFY_PAIR_LIMIT = {"sse": 5_000_000, "sae": 200_000}
"""Largest number of segment pairs (≈ N²/2) for which the exact search counts as cheap: a GA result is then
certified automatically, and the bootstrap repeats the exact search for every series."""


def exact_is_cheap(n_samples: int, objective: str) -> bool:
    """Whether the exact search on ``n_samples`` samples is cheap enough to run without being asked."""
    return n_samples * n_samples / 2 <= CERTIFY_PAIR_LIMIT[objective]


GRAM_FLOATS_PER_BATCH = 500_000


@dataclass
class ExactResult:
    """Optimal break vectors for p = 0…pmax.

    Attributes
    ----------
    breaks : dict[int, list[int]]
        The optimal breaks for each feasible p.
    objective : dict[int, float]
        Rg of those breaks (from the segment costs).
    evaluations : int
        Segment costs computed.
    seconds : float
    """

    breaks: dict[int, list[int]] = field(default_factory=dict)
    objective: dict[int, float] = field(default_factory=dict)
    evaluations: int = 0
    seconds: float = 0.0

    def for_p(self, p: int) -> SearchResult:
        """The optimum for ``p`` breaks in the form every search answers in."""
        return SearchResult(
            method="exact",
            breaks=self.breaks[p],
            objective=self.objective[p],
            evaluations=self.evaluations,
            seconds=self.seconds,
        )


def solve_exact(cost: SegmentCost, constraints: Constraints, pmax: int, progress=None) -> ExactResult:
    """Globally optimal breaks for every p in 0…pmax.

    Parameters
    ----------
    cost : SegmentCost
    constraints : Constraints
    pmax : int
        Largest number of breaks wanted; p above ``constraints.max_breaks()``
        is left out of the result.
    progress : callable, optional
        Called with the fraction done (0…1) now and then.
    """
    start = _time.perf_counter()
    evaluations_before = cost.evaluations
    n_samples = constraints.n_samples
    min_size = constraints.min_size
    pmax = min(pmax, constraints.max_breaks())
    result = ExactResult()
    if pmax < 0:
        return result

    break_ok = np.zeros(n_samples + 1, dtype=bool)
    break_ok[constraints.lowest_break : constraints.highest_break + 1] = True
    end_ok = break_ok.copy()
    end_ok[n_samples] = True

    levels = pmax + 2
    best = np.full((levels, n_samples + 1), np.inf)
    best[0, 0] = 0.0
    previous = np.full((levels, n_samples + 1), -1, dtype=np.int64)

    starts = np.r_[0, np.flatnonzero(break_ok)] if pmax > 0 else np.array([0])
    pairs_per_batch = GRAM_FLOATS_PER_BATCH // (cost.n_coef + 1) ** 2
    batch = max(1, pairs_per_batch // max(1, n_samples))
    for first in range(0, len(starts), batch):
        chunk = starts[first : first + batch]
        row_a, row_b = _feasible_pairs(chunk, min_size, end_ok, n_samples)
        costs = np.full((len(chunk), n_samples + 1), np.inf)
        costs[row_a, row_b] = cost.pair_costs(chunk[row_a], row_b)
        for i, a in enumerate(chunk):
            for k in [0] if a == 0 else range(1, pmax + 1):
                if not np.isfinite(best[k, a]):
                    continue
                candidate = best[k, a] + costs[i]
                if k + 1 <= pmax:
                    improve = candidate < best[k + 1]
                else:
                    improve = np.zeros(n_samples + 1, dtype=bool)
                    improve[n_samples] = candidate[n_samples] < best[k + 1, n_samples]
                best[k + 1, improve] = candidate[improve]
                previous[k + 1, improve] = a
        if progress is not None:
            progress(min(1.0, (first + len(chunk)) / len(starts)))

    for p in range(pmax + 1):
        value = best[p + 1, n_samples]
        if not np.isfinite(value):
            continue
        breaks = []
        position, level = n_samples, p + 1
        while level > 1:
            position = int(previous[level, position])
            breaks.append(position)
            level -= 1
        result.breaks[p] = sorted(breaks)
        result.objective[p] = float(value)
    result.evaluations = cost.evaluations - evaluations_before
    result.seconds = _time.perf_counter() - start
    return result


def _feasible_pairs(chunk: np.ndarray, min_size: int, end_ok: np.ndarray, n_samples: int):
    """Row index into ``chunk`` and end position b of every feasible (a, b) pair."""
    ends = np.flatnonzero(end_ok)
    rows, cols = [], []
    for i, a in enumerate(chunk):
        b = ends[ends >= a + min_size]
        rows.append(np.full(len(b), i))
        cols.append(b)
    return np.concatenate(rows), np.concatenate(cols)


SSE_SECONDS_PER_PAIR = 1.2e-6
"""Measured: about 1 µs per segment pair with M = 9 coefficients (2 cores, numpy), scaled by (M/9)²."""
SAE_SECONDS_PER_ROW = 4.0e-9
"""Measured: the sae residual passes cost about 4 ns per residual row and coefficient."""
SAE_BYTES_PER_PAIR = 30.0
"""Peak memory of the sae residual passes: about 30 bytes per (row, segment end) at one start."""
BASE_BYTES = 50e6


@dataclass(frozen=True)
class ExactCost:
    """A rough estimate of what an exact search costs (within a factor of about two)."""

    seconds: float
    bytes: float

    def describe(self) -> str:
        return f"about {format_seconds(self.seconds)} and {self.bytes / 1e9:.1f} GB"


def estimate_exact_cost(n_samples: int, n_coef: int, objective: str, pmax: int, min_size: int = 1) -> ExactCost:
    """Time and peak memory of :func:`solve_exact` on ``n_samples`` samples, before running it.

    ``sse`` costs O(N²·M²) time and O(pmax·N) memory; ``sae`` adds residual
    passes of O(N³·M) time and O(N²) memory at each start (the run that
    reached 6.4 GB at N = 20 000).
    """
    span = max(n_samples - min_size, 1)
    pairs = span * span / 2.0
    seconds = SSE_SECONDS_PER_PAIR * pairs * (n_coef / 9.0) ** 2 + 1e-7 * pairs * (pmax + 1)
    memory = BASE_BYTES + 16.0 * (pmax + 2) * (n_samples + 1) + 8.0 * GRAM_FLOATS_PER_BATCH * 4
    if objective == "sae":
        seconds += SAE_SECONDS_PER_ROW * span**3 / 6.0 * n_coef
        memory += SAE_BYTES_PER_PAIR * span * span
    return ExactCost(seconds=seconds, bytes=memory)


def format_seconds(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
