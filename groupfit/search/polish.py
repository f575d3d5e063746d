"""The local search that closes a GA run: shift, pair-shift and relocate moves until none improves Rg.

On a long run a break may lie anywhere among tens of thousands of positions,
and every position tried costs a residual pass over its two groups, so
trying all of them makes the search quadratic in N. A move with more than
:data:`COARSE_POSITIONS` positions to try is therefore searched coarse to
fine: every ``stride``-th position first, then every position within one
stride of the best of them and of the break's current place. Rg rises
steadily with the distance from a change of operating condition, so the
coarse pass lands in the right valley and the fine pass finds its floor; a
shorter range is searched position by position, as before.
"""

from __future__ import annotations

import itertools
from typing import Protocol, Sequence

import numpy as np

from groupfit.grouping import Constraints

COARSE_POSITIONS = 1024
"""A move with more positions to try than this is searched every ``ceil(range / COARSE_POSITIONS)``-th first."""


def improves(new: float, old: float) -> bool:
    """Whether Rg ``new`` is lower than ``old`` by more than rounding (a relative 1e-12)."""
    return new < old * (1 - 1e-12) - 1e-300


class BreakObjective(Protocol):
    def totals(self, break_vectors) -> list[float]: ...


def polish_breaks(
    breaks: list[int],
    value: float,
    objective: BreakObjective,
    constraints: Constraints,
    max_relocated: int = 2,
    beam: int = 4,
) -> tuple[list[int], float]:
    """Local search from ``breaks`` until no move improves Rg.

    *Shift* moves one break to its best position between its neighbours.
    *Relocate* removes up to ``max_relocated`` breaks and inserts as many
    again, one at a time, keeping the ``beam`` best partial vectors at each
    insertion; each resulting vector is shift-polished before it is compared,
    so a relocation that only pays once its neighbours have moved is found.
    """
    breaks, value = _shift_polish(list(breaks), value, objective, constraints)
    improved = True
    while improved:
        improved = False
        for size in range(1, min(max_relocated, len(breaks)) + 1):
            for removed in itertools.combinations(range(len(breaks)), size):
                rest = [b for i, b in enumerate(breaks) if i not in removed]
                for trial in _beam_insert(rest, size, beam, objective, constraints):
                    trial, trial_value = _shift_polish(trial, objective.totals([trial])[0], objective, constraints)
                    if improves(trial_value, value):
                        breaks, value, improved = trial, trial_value, True
                        break
                if improved:
                    break
            if improved:
                break
    return breaks, value


def _beam_insert(
    rest: list[int], count: int, beam: int, objective: BreakObjective, constraints: Constraints
) -> list[list[int]]:
    """Insert ``count`` breaks into ``rest`` one at a time, keeping the ``beam`` best at each step."""
    frontier = [rest]
    for _ in range(count):
        expanded = {tuple(c) for partial in frontier for c in _insertions(partial, constraints)}
        if not expanded:
            return []
        candidates = [list(c) for c in sorted(expanded)]
        values = np.asarray(objective.totals(candidates))
        frontier = [candidates[k] for k in np.argsort(values, kind="stable")[:beam]]
    return frontier


def _shift_polish(
    breaks: list[int], value: float, objective: BreakObjective, constraints: Constraints, pair_window: int = 8
) -> tuple[list[int], float]:
    """Shift single breaks, then neighbouring pairs within ``±pair_window``, until neither improves."""
    improved = True
    while improved:
        improved = False
        for j in range(len(breaks)):
            candidate, candidate_value = _best_shift(breaks, j, objective, constraints)
            if candidate is not None and improves(candidate_value, value):
                breaks, value, improved = candidate, candidate_value, True
        if improved:
            continue
        for j in range(len(breaks) - 1):
            candidates = _pair_candidates(breaks, j, constraints, pair_window)
            if not candidates:
                continue
            values = objective.totals(candidates)
            k = int(np.argmin(values))
            if improves(values[k], value):
                breaks, value, improved = candidates[k], values[k], True
    return breaks, value


def _best_shift(
    breaks: list[int], j: int, objective: BreakObjective, constraints: Constraints
) -> tuple[list[int] | None, float]:
    """Break j at its best position between its neighbours (coarse to fine on a long range), and its Rg."""
    first, last = shift_range(breaks, j, constraints)
    stride = _stride(last - first + 1)
    positions = set(range(first, last + 1, stride))
    tried: dict[int, float] = {}
    while True:
        fresh = sorted(positions - tried.keys() - {breaks[j]})
        if fresh:
            vectors = [breaks[:j] + [b] + breaks[j + 1 :] for b in fresh]
            tried.update(zip(fresh, objective.totals(vectors)))
        if not tried:
            return None, float("inf")
        best = min(tried, key=lambda b: (tried[b], b))
        if stride == 1:
            return breaks[:j] + [best] + breaks[j + 1 :], tried[best]
        positions = {
            b
            for centre in (best, breaks[j])
            for b in range(max(first, centre - stride + 1), min(last, centre + stride - 1) + 1)
        }
        stride = 1


def _stride(positions: int) -> int:
    return max(1, -(-positions // COARSE_POSITIONS))


def shift_range(breaks: Sequence[int], j: int, constraints: Constraints) -> tuple[int, int]:
    """Positions break j may take with the other breaks where they are."""
    left = breaks[j - 1] if j > 0 else 0
    right = breaks[j + 1] if j + 1 < len(breaks) else constraints.n_samples
    return (
        max(left + constraints.min_size, constraints.lowest_break),
        min(right - constraints.min_size, constraints.highest_break),
    )


def _pair_candidates(breaks: list[int], j: int, constraints: Constraints, window: int) -> list[list[int]]:
    """Break vectors with breaks j and j+1 moved together, each by at most ``window`` samples."""
    min_size = constraints.min_size
    low, _ = shift_range(breaks, j, constraints)
    _, high = shift_range(breaks, j + 1, constraints)
    candidates = []
    for first in range(max(low, breaks[j] - window), breaks[j] + window + 1):
        for second in range(max(first + min_size, breaks[j + 1] - window), min(high, breaks[j + 1] + window) + 1):
            if (first, second) != (breaks[j], breaks[j + 1]):
                candidates.append(breaks[:j] + [first, second] + breaks[j + 2 :])
    return candidates


def _insertions(breaks: list[int], constraints: Constraints) -> list[list[int]]:
    """Feasible vectors with one more break than ``breaks``: every position of a gap, every stride-th of a
    long one (the shift polish that follows each relocation places it to the sample)."""
    edges = [0, *breaks, constraints.n_samples]
    candidates = []
    for k in range(len(edges) - 1):
        first = max(edges[k] + constraints.min_size, constraints.lowest_break)
        last = min(edges[k + 1] - constraints.min_size, constraints.highest_break)
        stride = _stride(last - first + 1)
        candidates.extend(breaks[:k] + [b] + breaks[k:] for b in range(first, last + 1, stride))
    return candidates


__all__ = ["COARSE_POSITIONS", "improves", "polish_breaks", "shift_range"]
