"""Hard and soft groups of a modelling run, and the constraints on break points.

Conventions (docs/methods.md §1): samples are numbered 1…N. A hard break ``b`` is the
*last* sample of its hard group, so with breaks ``b_1 < … < b_p`` (``b_0 = 0``,
``b_{p+1} = N``) hard group j holds samples ``b_{j-1}+1 … b_j``. Soft group 1 is
``1 … b_1``; soft group j ≥ 2 is ``b_{j-1}-n+1 … b_j``: it starts n samples
before its hard group, so neighbouring soft groups share n samples. In service
the later group serves the shared samples, so group j *serves*
``b_{j-1}-n+1 … b_j-n`` (the last group serves up to N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from groupfit.errors import InputError

DEFAULT_SOFT_OFFSET = 3
"""n: samples by which a soft group reaches back into the hard group before it (the paper's n)."""
DEFAULT_SPACING = 3.0
"""c: every hard group holds more than c·M samples, M the coefficients per group."""
MAX_SPACING = 1.0e6
"""The largest c: a group of more than a million samples per coefficient is a slip, not a spacing."""


def min_group_size(c: float, n_coef: int, n: int = 0) -> int:
    """Smallest allowed hard-group size: more than ``c·M`` samples, and whatever c, more than ``M``.

    Every group stays over-determined (more samples than coefficients) even
    with ``c < 1``: with ``c = 0`` a group of M samples would be interpolated
    exactly and its residual would mean nothing. The group must also be longer
    than the soft offset ``n``, or the next soft group would reach back past
    its start.
    """
    if not (math.isfinite(c) and 0 <= c <= MAX_SPACING):
        raise InputError(f"spacing coefficient c = {c:g} must be a number from 0 to {MAX_SPACING:g}")
    return max(int(math.floor(c * n_coef + 1e-12)) + 1, n_coef + 1, n + 1)


def check_spacing(n: int, c: float) -> None:
    """Refuse a soft offset ``n`` that is not a whole number ≥ 0 or a spacing coefficient ``c`` outside
    0 … :data:`MAX_SPACING` (one line naming the value)."""
    min_group_size(c, 1)
    if int(n) != n or n < 0:
        raise InputError(f"n = {n!r}: the soft offset must be a whole number ≥ 0")


@dataclass(frozen=True)
class Constraints:
    """Feasible break vectors for N samples.

    A break vector is feasible when every hard group (the first and the last
    included) has at least ``min_size`` samples and every break lies strictly
    between ``n`` and ``N``.
    """

    n_samples: int
    n: int
    min_size: int

    @classmethod
    def for_model(cls, n_samples: int, n: int, c: float, n_coef: int) -> "Constraints":
        if n < 0:
            raise InputError(f"soft offset n = {n} must not be negative")
        return cls(n_samples=int(n_samples), n=int(n), min_size=min_group_size(c, n_coef, int(n)))

    @property
    def lowest_break(self) -> int:
        return max(self.min_size, self.n + 1)

    @property
    def highest_break(self) -> int:
        return self.n_samples - self.min_size

    def max_breaks(self) -> int:
        """Largest p for which a feasible break vector exists (-1 if even p = 0 is not)."""
        if self.n_samples < self.min_size:
            return -1
        if self.lowest_break > self.highest_break:
            return 0
        return 1 + (self.highest_break - self.lowest_break) // self.min_size

    def is_feasible(self, breaks: Sequence[int]) -> bool:
        b = np.asarray(breaks, dtype=int)
        if b.size == 0:
            return self.n_samples >= self.min_size
        edges = np.concatenate(([0], b, [self.n_samples]))
        return bool(np.all(np.diff(edges) >= self.min_size) and b[0] > self.n and b[-1] < self.n_samples)

    def require(self, p: int, c: float, n_coef: int) -> None:
        """Raise a clear InputError when p breaks cannot fit."""
        if p < 0:
            raise InputError(f"p = {p}: the number of breaks must be 0 or more")
        largest = self.max_breaks()
        if p > largest:
            if largest < 0:
                lower = "n (the soft offset)" if self.n + 1 >= self.min_size and self.n >= c * n_coef else "c"
                hint = f"no model can be fitted: give more samples or lower {lower}"
            else:
                hint = f"the largest feasible p is {largest}"
            raise InputError(
                f"p = {p} breaks do not fit N = {self.n_samples} samples with c = {c:g}, "
                f"M = {n_coef} and n = {self.n} (each hard group needs at least {self.min_size} samples: "
                f"more than c·M = {c * n_coef:g}, than M and than n): {hint}"
            )


def hard_groups(breaks: Sequence[int], n_samples: int) -> list[tuple[int, int]]:
    """Hard groups as 1-based inclusive ``(first, last)`` pairs."""
    edges = [0, *map(int, breaks), int(n_samples)]
    return [(edges[j] + 1, edges[j + 1]) for j in range(len(edges) - 1)]


def soft_groups(breaks: Sequence[int], n_samples: int, n: int) -> list[tuple[int, int]]:
    """Soft groups (the rows each coefficient vector is fitted on), 1-based inclusive."""
    edges = [0, *map(int, breaks), int(n_samples)]
    return [(1 if j == 0 else edges[j] - n + 1, edges[j + 1]) for j in range(len(edges) - 1)]


def served_ranges(breaks: Sequence[int], n_samples: int, n: int) -> list[tuple[int, int]]:
    """Samples each group serves (and is scored on): a partition of 1…N."""
    soft = soft_groups(breaks, n_samples, n)
    last = len(soft) - 1
    return [(first, end if j == last else end - n) for j, (first, end) in enumerate(soft)]


def serving_group_index(breaks: Sequence[int], n_samples: int, n: int, length: int | None = None) -> np.ndarray:
    """0-based group index serving each sample 1…length (samples past N: the last group)."""
    length = n_samples if length is None else length
    starts = np.array([first for first, _ in served_ranges(breaks, n_samples, n)])
    samples = np.arange(1, length + 1)
    return np.searchsorted(starts, samples, side="right") - 1


def bumpless(prediction: np.ndarray, groups: np.ndarray, blend_samples: int) -> np.ndarray:
    """``prediction`` (each sample's serving group's) with the run-time rule's bumpless transfer after each switch.

    At a switch at sample s (``groups``: 0-based, non-decreasing) the rule
    keeps the gap ``g`` from its last output to the new group's prediction
    and serves ``prediction + (B − k) / (B + 1) · g`` at the switch's sample
    s + k, k = 0 … B − 1 (``B = blend_samples``; docs/switching.md), in the
    rule's order of operations, so that the result is the rule's in double
    precision.
    """
    out = np.array(prediction, dtype=float)
    groups = np.asarray(groups)
    if blend_samples <= 0:
        return out
    for switch in np.flatnonzero(np.diff(groups) != 0) + 1:
        gap = out[switch - 1] - out[switch]
        for k in range(blend_samples):
            i = switch + k
            if i >= len(groups) or (k and groups[i] != groups[switch]):
                break
            out[i] = out[i] + float(blend_samples - k) / float(blend_samples + 1) * gap
    return out


def block_design(
    inputs: np.ndarray, groups: np.ndarray, n_groups: int, *, fit_intercept: bool, shared: np.ndarray
) -> np.ndarray:
    """Each group's own inputs (and intercept) in its own columns, rows by ``groups``; then the ``shared`` inputs,
    one column each for every group."""
    own = inputs[:, ~shared]
    block = np.column_stack([np.ones(len(inputs)), own]) if fit_intercept else own
    design = np.zeros((len(inputs), n_groups * block.shape[1]))
    for g in range(n_groups):
        rows = groups == g
        design[rows, g * block.shape[1] : (g + 1) * block.shape[1]] = block[rows]
    return np.column_stack([design, inputs[:, shared]])


def shared_mask(shared_columns, n_features: int, breaks: Sequence[int]) -> np.ndarray | None:
    """``shared_columns`` as a mask, or None when no column is shared (or the model has one group)."""
    if shared_columns is None or not breaks:
        return None
    shared = np.asarray(shared_columns, dtype=bool)
    if shared.shape != (n_features,):
        raise InputError(f"shared_columns marks {shared.size} columns; X has {n_features}")
    return shared if shared.any() else None


def shared_fit(X: np.ndarray, y: np.ndarray, groups: np.ndarray, n_groups: int, shared, *, intercept: bool):
    """The shared inputs' coefficients fitted with each group's own on the groups ``groups``; and the own inputs
    with what the shared ones leave of ``y``, for each group's refit: ``(own, rest, gamma)``; ``(X, y, None)``
    when nothing is shared (``shared`` None)."""
    if shared is None:
        return X, y, None
    design = block_design(X, groups, n_groups, fit_intercept=intercept, shared=shared)
    gamma = np.linalg.lstsq(design, y, rcond=None)[0][-int(shared.sum()) :]
    return X[:, ~shared], y - X[:, shared] @ gamma, gamma
