"""The dynamic programme over break positions that both exact searches share.

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
from typing import Iterator

import numpy as np

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.base import SearchResult

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
        Segment costs computed exactly.
    seconds : float
    bounded : int
        Segments only bounded from below and never costed exactly (the
        bounded ``sae`` search, :mod:`groupfit.search.bounded`; 0 otherwise).
    pruning : dict
        The bounded search's counts: ``segments`` (feasible), ``left`` (after
        each bound stage), ``costed`` (exactly); empty otherwise.
    """

    breaks: dict[int, list[int]] = field(default_factory=dict)
    objective: dict[int, float] = field(default_factory=dict)
    evaluations: int = 0
    seconds: float = 0.0
    bounded: int = 0
    pruning: dict = field(default_factory=dict)

    def for_p(self, p: int) -> SearchResult:
        """The optimum for ``p`` breaks in the form every search answers in."""
        return SearchResult(
            method="exact",
            breaks=self.breaks[p],
            objective=self.objective[p],
            evaluations=self.evaluations,
            seconds=self.seconds,
        )


class PathTable:
    """``best[k][b]``: least cost of k groups ending at b, with the start that reached it.

    Parameters
    ----------
    n_samples, pmax : int
    """

    def __init__(self, n_samples: int, pmax: int):
        self.n_samples = n_samples
        self.pmax = pmax
        self.best = np.full((pmax + 2, n_samples + 1), np.inf)
        self.best[0, 0] = 0.0
        self.previous = np.full((pmax + 2, n_samples + 1), -1, dtype=np.int64)

    def levels(self, a: int) -> range:
        """The numbers of groups k that can end at hard break a (k = 0 only at the start)."""
        return range(0, 1) if a == 0 else range(1, self.pmax + 1)

    def relax(self, a: int, costs: np.ndarray) -> None:
        """Extend every path ending at a by one group ending at each b (``costs[b]``, inf if none)."""
        n_samples, pmax = self.n_samples, self.pmax
        for k in self.levels(a):
            if not np.isfinite(self.best[k, a]):
                continue
            candidate = self.best[k, a] + costs
            if k + 1 <= pmax:
                improve = candidate < self.best[k + 1]
            else:
                improve = np.zeros(n_samples + 1, dtype=bool)
                improve[n_samples] = candidate[n_samples] < self.best[k + 1, n_samples]
            self.best[k + 1, improve] = candidate[improve]
            self.previous[k + 1, improve] = a

    def result(self) -> ExactResult:
        """The optimal breaks and Rg of every p that reached N."""
        result = ExactResult()
        n_samples = self.n_samples
        for p in range(self.pmax + 1):
            value = self.best[p + 1, n_samples]
            if not np.isfinite(value):
                continue
            breaks = []
            position, level = n_samples, p + 1
            while level > 1:
                position = int(self.previous[level, position])
                breaks.append(position)
                level -= 1
            result.breaks[p] = sorted(breaks)
            result.objective[p] = float(value)
        return result


def segment_starts(constraints: Constraints, pmax: int) -> tuple[np.ndarray, np.ndarray]:
    """Every position a group can start after (0 and the feasible breaks), and where one can end."""
    n_samples = constraints.n_samples
    break_ok = np.zeros(n_samples + 1, dtype=bool)
    break_ok[constraints.lowest_break : constraints.highest_break + 1] = True
    end_ok = break_ok.copy()
    end_ok[n_samples] = True
    starts = np.r_[0, np.flatnonzero(break_ok)] if pmax > 0 else np.array([0])
    return starts, end_ok


def start_chunks(
    starts: np.ndarray, end_ok: np.ndarray, *, min_size: int, floats_per_pair: int
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Starts in batches of about GRAM_FLOATS_PER_BATCH floats, with every feasible ``(row, b)`` pair of each.

    Yields ``(chunk, rows, b)``: the starts of the batch, the row of each pair's
    start in ``chunk`` and each pair's end.
    """
    n_samples = len(end_ok) - 1
    batch = max(1, GRAM_FLOATS_PER_BATCH // max(1, floats_per_pair) // max(1, n_samples))
    ends = np.flatnonzero(end_ok)
    for first in range(0, len(starts), batch):
        chunk = starts[first : first + batch]
        rows, cols = [], []
        for i, a in enumerate(chunk):
            b = ends[ends >= a + min_size]
            rows.append(np.full(len(b), i))
            cols.append(b)
        yield chunk, np.concatenate(rows), np.concatenate(cols)


def solve_all_pairs(cost: SegmentCost, constraints: Constraints, pmax: int, progress=None) -> ExactResult:
    """Globally optimal breaks for every p in 0…pmax, every feasible segment costed.

    The parameters are those of :func:`groupfit.search.exact.solve_exact`.
    """
    start = _time.perf_counter()
    evaluations_before = cost.evaluations
    n_samples = constraints.n_samples
    pmax = min(pmax, constraints.max_breaks())
    if pmax < 0:
        return ExactResult()
    table = PathTable(n_samples, pmax)
    starts, end_ok = segment_starts(constraints, pmax)
    done = 0
    for chunk, rows, b in start_chunks(
        starts, end_ok, min_size=constraints.min_size, floats_per_pair=(cost.n_coef + 1) ** 2
    ):
        costs = np.full((len(chunk), n_samples + 1), np.inf)
        costs[rows, b] = cost.pair_costs(chunk[rows], b)
        for i, a in enumerate(chunk):
            table.relax(int(a), costs[i])
        done += len(chunk)
        if progress is not None:
            progress(min(1.0, done / len(starts)))
    result = table.result()
    result.evaluations = cost.evaluations - evaluations_before
    result.seconds = _time.perf_counter() - start
    return result
