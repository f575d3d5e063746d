"""Exact ``sae`` break search that costs exactly only the segments an optimum can use.

The ``sae`` cost of a segment is the sum of absolute residuals of its
least-squares fit over the rows it serves: unlike ``sse`` it has no prefix-sum
shortcut, so costing every one of the N²/2 segments takes O(N³) time. This
search reaches the same optimum by bounding (docs/methods.md, "The exact
search for sae"):

1. **Incumbents.** The exact ``sse`` optimum for every p (prefix sums, cheap)
   and any break vectors the caller knows (the GA's) are scored on ``sae``;
   the best per p is an upper bound ``U_p`` on the ``sae`` optimum, and the
   signs of its residuals serve the bounds.
2. **A lower bound of every segment** in O(K·M) from prefix sums
   (:mod:`groupfit.search.sae_bounds`), stored as float32 rounded down.
3. **Ruling out.** With F and G the least bounded costs from 0 to a and from
   b to N, a segment (a, b) is dropped when ``F[k][a] + bound(a, b) +
   G[p−k][b] > U_p`` for every level k and every p. The segments left get
   finer bounds (grids of :data:`GRID_STEPS`) and the test is repeated.
4. **A forward pass** runs the dynamic programme of
   :mod:`groupfit.search.dynprog` with exact costs of the segments left, each
   rechecked with the exact F of the paths that reach its start.

No segment of an optimal path is ever dropped: its bound and the bounds of
the rest of that path are below their costs, so its path bound is at most
the optimum, which is at most ``U_p``. The dynamic programme over the
segments left therefore returns the optimum (and the same break vector among
ties, since it visits them in the same order) that costing every segment
returns.

Time: two passes of least-squares fits over the N²/2 segments (the ``sse``
optimum and the cheap bounds), the grid bounds and residual passes of the
segments left. How many are left depends on the data: where the optimum's
groups differ clearly from their neighbours almost every segment is dropped
unseen; where many break vectors score within a few per cent of the optimum
(16 collinear sensors on a smooth measured run) most are left and the search
costs about what costing every segment does. Memory: float32 bounds of every
segment, 2·N² bytes.
"""

from __future__ import annotations

import time as _time
from typing import Mapping, Sequence

import numpy as np

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.dynprog import ExactResult, PathTable, segment_starts, solve_all_pairs, start_chunks
from groupfit.search.sae_bounds import RELATIVE_SLACK, SignBounds, served_signs

GRID_STEPS = (64, 8)
"""Grid steps of the finer bounds (:meth:`SignBounds.grid_lower`), applied in turn to the segments left."""
GRID_FLOATS = 2_000_000
"""Largest (signs × blocks × segments) array of one grid bound call."""


def solve_bounded(
    cost: SegmentCost,
    constraints: Constraints,
    pmax: int,
    *,
    incumbents: Mapping[int, Sequence[int]] | None = None,
    every_p: bool = True,
    progress=None,
) -> ExactResult:
    """Globally optimal ``sae`` breaks for every p in 0…pmax (the result :func:`solve_all_pairs` gives).

    Parameters
    ----------
    cost : SegmentCost
        With ``objective="sae"``.
    constraints : Constraints
    pmax : int
    incumbents : mapping of p to a break vector, optional
        Feasible break vectors already found (a GA's); they tighten the bounds.
        Vectors that are infeasible or have another number of breaks are ignored.
    every_p : bool
        False: answer p = pmax only, which bounds (and so rules out) more segments.
    progress : callable, optional
        Called with the fraction done (0…1) now and then.
    """
    if cost.objective != "sae":
        raise ValueError(f"the bounded search is for the sae objective, got {cost.objective!r}")
    start = _time.perf_counter()
    evaluations_before = cost.evaluations
    pmax = min(pmax, constraints.max_breaks())
    if pmax < 0:
        return ExactResult()
    stage = _stages(progress, 3 + len(GRID_STEPS))
    least_squares = solve_all_pairs(cost.with_objective("sse"), constraints, pmax, progress=stage(0))
    upper, signs = _incumbents(cost, constraints, least_squares.breaks, incumbents or {})
    if not every_p:
        upper = {pmax: upper[pmax]}
    bounds = SignBounds(cost, signs)
    table = BoundTable(constraints, pmax)
    table.compute(cost, bounds, progress=stage(1))
    left = [table.prune(upper)]
    for index, step in enumerate(GRID_STEPS):
        table.refine(cost, bounds, step, progress=stage(2 + index))
        left.append(table.prune(upper))
    result, costed = _forward(cost, table, pmax, upper, stage(2 + len(GRID_STEPS)))
    for p in set(result.breaks) - set(upper):  # not bounded: not certified
        del result.breaks[p], result.objective[p]
    result.evaluations = cost.evaluations - evaluations_before
    result.bounded = table.total - costed
    result.pruning = {"segments": table.total, "left": left, "costed": costed}
    result.seconds = _time.perf_counter() - start
    return result


def _stages(progress, count: int):
    """Progress callbacks for ``count`` passes of equal weight."""

    def stage(index: int):
        if progress is None:
            return None
        return lambda fraction: progress((index + fraction) / count)

    return stage


def _incumbents(cost, constraints, least_squares: Mapping[int, list[int]], given: Mapping[int, Sequence[int]]):
    """U_p, the best ``sae`` among the known break vectors of each p, and their residual signs."""
    upper: dict[int, float] = {}
    signs = []
    for p, breaks in least_squares.items():
        options = [list(breaks)]
        extra = [int(b) for b in given.get(p, [])]
        if len(extra) == p and constraints.is_feasible(extra) and extra != options[0]:
            options.append(extra)
        values = [cost.total(option) for option in options]
        best = int(np.argmin(values))
        upper[p] = float(values[best])
        signs.append(served_signs(cost, options[best]))
    return upper, signs


class BoundTable:
    """A lower bound of every feasible segment's ``sae``, one float32 row per start (inf: ruled out).

    Bounds are rounded down to float32. A segment is ruled out when no path
    through it can reach U_p by the bounds: ``F[k][a] + bound(a, b) + G[p−k][b] > U_p``
    for every level k and every p, with F and G the least bounded costs from
    0 to a and from b to N over the segments not yet ruled out. The segments
    of an optimal path are never ruled out (their bounds are below their
    costs, so each path bound is at most the optimum), which is why F and G
    may be taken over the segments left.
    """

    def __init__(self, constraints: Constraints, pmax: int):
        self.n_samples = constraints.n_samples
        self.min_size = constraints.min_size
        self.pmax = pmax
        self.starts, self.end_ok = segment_starts(constraints, pmax)
        self.ends = np.flatnonzero(self.end_ok)
        self.rows: dict[int, np.ndarray] = {}
        self.total = 0

    def ends_after(self, a: int) -> np.ndarray:
        return self.ends[self.ends >= a + self.min_size]

    def compute(self, cost: SegmentCost, bounds: SignBounds, progress=None) -> None:
        """The cheap bound (:meth:`SignBounds.lower`) of every feasible segment."""
        floats = max((cost.n_coef + 1) ** 2, bounds.n_signs * (cost.n_coef + 1))
        done = 0
        for chunk, rows, b in start_chunks(self.starts, self.end_ok, min_size=self.min_size, floats_per_pair=floats):
            lo = cost.soft_group_first(chunk[rows])
            coef, _ = cost.pair_fits(lo, b)
            lower = _round_down(bounds.lower(lo, cost.served_last(b), coef))
            for i, a in enumerate(chunk):
                self.rows[int(a)] = lower[rows == i]
            done += len(chunk)
            if progress is not None:
                progress(done / len(self.starts))
        self.total = sum(len(row) for row in self.rows.values())

    def refine(self, cost: SegmentCost, bounds: SignBounds, step: int, progress=None) -> None:
        """Raise the bound of every segment left to the larger of it and the grid bound of ``step``."""
        for done, a in enumerate(self.starts):
            row = self.rows[int(a)]
            alive = np.flatnonzero(np.isfinite(row))
            if len(alive) == 0:
                continue
            ends = self.ends_after(int(a))
            lo = int(cost.soft_group_first(np.array([a]))[0])
            per_call = max(1, GRID_FLOATS // (bounds.n_signs * (self.n_samples // step + 2)))
            for first in range(0, len(alive), per_call):
                members = alive[first : first + per_call]
                b = ends[members]
                coef, _ = cost.pair_fits(np.full(len(b), lo), b)
                grid = _round_down(bounds.grid_lower(lo, cost.served_last(b), coef, step))
                row[members] = np.maximum(row[members], grid)
            if progress is not None and done % 256 == 0:
                progress(done / len(self.starts))

    def to_end(self) -> np.ndarray:
        """``G[j][a]``: least bounded cost of j groups from hard break a to N."""
        to_end = np.full((self.pmax + 2, self.n_samples + 1), np.inf)
        to_end[0, self.n_samples] = 0.0
        for a in self.starts[::-1]:  # every b > a is final
            ends = self.ends_after(int(a))
            if len(ends):
                to_end[1:, a] = np.min(self.rows[int(a)][None, :] + to_end[:-1, ends], axis=1)
        return to_end

    def from_start(self) -> np.ndarray:
        """``F[k][b]``: least bounded cost of k groups from 0 to hard break b."""
        table = PathTable(self.n_samples, self.pmax)
        for a in self.starts:
            costs = np.full(self.n_samples + 1, np.inf)
            costs[self.ends_after(int(a))] = self.rows[int(a)]
            table.relax(int(a), costs)
        return table.best

    def prune(self, upper: Mapping[int, float]) -> int:
        """Rule out the segments no bounded path through reaches U_p; the number left."""
        limits = reach_limits(self.to_end(), upper)
        start_bound = self.from_start()
        left = 0
        for a in self.starts:
            row = self.rows[int(a)]
            ends = self.ends_after(int(a))
            reach = _reach(start_bound, limits, int(a))
            row[row + reach[ends] > 0.0] = np.inf
            left += int(np.isfinite(row).sum())
        return left


def _round_down(values: np.ndarray) -> np.ndarray:
    single = values.astype(np.float32)
    return np.where(single > values, np.nextafter(single, np.float32(-np.inf)), single)


def reach_limits(to_end: np.ndarray, upper: Mapping[int, float]) -> np.ndarray:
    """``H[k][b] = min_p G[p−k][b] − U_p``: a segment ending at b as group k+1 is left if ``F + bound + H ≤ 0``."""
    levels, width = to_end.shape
    limits = np.full((levels - 1, width), np.inf)
    for p, value in upper.items():
        allowance = value * (1.0 + RELATIVE_SLACK) + RELATIVE_SLACK
        for k in range(p + 1):
            limits[k] = np.minimum(limits[k], to_end[p - k] - allowance)
    return limits


def _reach(start_bound: np.ndarray, limits: np.ndarray, a: int) -> np.ndarray:
    """``min_k F[k][a] + H[k][·]`` over the levels that can end at a."""
    levels = range(0, 1) if a == 0 else range(1, limits.shape[0])
    return np.min(start_bound[list(levels), a][:, None] + limits[list(levels)], axis=0)


def _forward(cost, table: BoundTable, pmax: int, upper: Mapping[int, float], progress=None):
    """The dynamic programme with exact costs of the segments still left.

    Each segment is rechecked against the exact costs of the paths that reach
    its start. Starts closer than ``min_size`` cannot precede one another, so
    a block of them is decided at once and its segments costed in one call.
    """
    n_samples = table.n_samples
    limits = reach_limits(table.to_end(), upper)
    paths = PathTable(n_samples, pmax)
    starts = table.starts
    costed = 0
    first = 0
    while first < len(starts):
        stop = int(np.searchsorted(starts, starts[first] + table.min_size))  # none of these precedes another
        block, first = starts[first:stop], stop
        pair_a, pair_b = [], []
        for a in block:
            ends = table.ends_after(int(a))
            keep = ends[table.rows[int(a)] + _reach(paths.best, limits, int(a))[ends] <= 0.0]
            pair_a.append(np.full(len(keep), a))
            pair_b.append(keep)
        a_all, b_all = np.concatenate(pair_a), np.concatenate(pair_b)
        values = cost.pair_costs(a_all, b_all) if len(a_all) else np.empty(0)
        costed += len(a_all)
        for a in block:
            costs = np.full(n_samples + 1, np.inf)
            mine = a_all == a
            costs[b_all[mine]] = values[mine]
            paths.relax(int(a), costs)
        if progress is not None:
            progress(first / len(starts))
    return paths.result(), costed
