"""Exact break-point search: the global optimum of Rg for every p up to pmax.

Both objectives run the dynamic programme of :mod:`groupfit.search.dynprog`.
``sse`` costs every segment from prefix sums; ``sae`` costs exactly only the
segments that bounds cannot rule out (:mod:`groupfit.search.bounded`), with
``method="all-pairs"`` as the reference that costs every one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost, segment_table_bytes
from groupfit.search.bounded import solve_bounded
from groupfit.search.dynprog import GRAM_FLOATS_PER_BATCH, ExactResult, solve_all_pairs

CERTIFY_PAIR_LIMIT = {"sse": 5_000_000, "sae": 200_000}
"""Largest number of segment pairs (≈ N²/2) for which the exact search counts as cheap: a GA result is then
certified automatically, and the bootstrap repeats the exact search for every series."""
EXACT_METHODS = ("auto", "all-pairs", "bounded")


def exact_is_cheap(n_samples: int, objective: str) -> bool:
    """Whether the exact search on ``n_samples`` samples is cheap enough to run without being asked."""
    return n_samples * n_samples / 2 <= CERTIFY_PAIR_LIMIT[objective]


def solve_exact(
    cost: SegmentCost,
    constraints: Constraints,
    pmax: int,
    progress=None,
    *,
    incumbents: Mapping[int, Sequence[int]] | None = None,
    every_p: bool = True,
    method: str = "auto",
) -> ExactResult:
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
    incumbents : mapping of p to a break vector, optional
        Break vectors already found (a GA's): the bounded search starts from them.
    every_p : bool
        False: only p = pmax is wanted (the bounded search then answers only that p, faster).
    method : {"auto", "all-pairs", "bounded"}
        ``"auto"``: bounded for ``sae``, every segment costed for ``sse``.
        ``"all-pairs"`` costs every segment (the reference); ``"bounded"`` needs ``sae``.
    """
    if method not in EXACT_METHODS:
        raise ValueError(f"method must be one of {EXACT_METHODS}, got {method!r}")
    if method == "bounded" or (method == "auto" and cost.objective == "sae"):
        return solve_bounded(cost, constraints, pmax, incumbents=incumbents, every_p=every_p, progress=progress)
    return solve_all_pairs(cost, constraints, pmax, progress=progress)


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

    ``sse`` costs O(N²·M²) time and O(pmax·N) memory; for ``sae`` this is
    the worst case, every segment costed (residual passes of O(N³·M) time and
    O(N²) memory at each start): the bounded search usually costs a few times
    ``sse`` but how many segments it rules out depends on the data.
    """
    span = max(n_samples - min_size, 1)
    pairs = span * span / 2.0
    seconds = SSE_SECONDS_PER_PAIR * pairs * (n_coef / 9.0) ** 2 + 1e-7 * pairs * (pmax + 1)
    memory = BASE_BYTES + 16.0 * (pmax + 2) * (n_samples + 1) + 8.0 * GRAM_FLOATS_PER_BATCH * 4
    memory += segment_table_bytes(n_samples, n_coef)
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
