"""Break-point searches over a :class:`~groupfit.objective.SegmentCost`.

:mod:`~groupfit.search.base` holds what both share (settings, the result
form); :mod:`~groupfit.search.exact` and :mod:`~groupfit.search.ga` (DEAP,
imported only when used) the two searches.
"""

from groupfit.search.base import GA_DEFAULTS, METHODS, GASettings, SearchResult, SearchSettings
from groupfit.search.exact import ExactResult, solve_exact

__all__ = ["ExactResult", "GASettings", "GA_DEFAULTS", "METHODS", "SearchResult", "SearchSettings", "solve_exact"]
