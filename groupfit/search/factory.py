"""One way to ask for a break search: ``make_search(settings, seed=...).run(cost, constraints, p)``.

The exact search and the genetic algorithm answer the same call with a
:class:`~groupfit.search.base.SearchResult`, so the caller does not branch on
the method. Whether the
exact search is cheap enough to run unasked (to certify a GA result) is
decided in :mod:`groupfit.search.exact`.
"""

from __future__ import annotations

from typing import Callable

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.base import SearchResult, SearchSettings
from groupfit.search.exact import solve_exact
from groupfit.search.ga import GeneticSearch


class ExactSearch:
    """The exact dynamic-programming search behind the common ``run`` call."""

    method = "exact"

    def run(
        self,
        cost: SegmentCost,
        constraints: Constraints,
        p: int,
        progress: Callable[[float], None] | None = None,
    ) -> SearchResult:
        """The optimal p breaks; ``progress(fraction)`` is called now and then."""
        return solve_exact(cost, constraints, p, progress=progress, every_p=False).for_p(p)


def make_search(settings: SearchSettings, *, seed: int | None = None):
    """The search ``settings.method`` names, seeded by ``seed`` (default ``settings.seed``).

    Returns an object with ``run(cost, constraints, p, progress=None)``: :class:`ExactSearch`, or a
    :class:`groupfit.search.ga.GeneticSearch` with ``settings.ga``.
    """
    if settings.method == "exact":
        return ExactSearch()
    return GeneticSearch.from_settings(settings.ga, seed=settings.seed if seed is None else seed)
