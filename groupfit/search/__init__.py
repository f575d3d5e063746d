"""Break-point searches over a :class:`~groupfit.objective.SegmentCost`."""

from groupfit.search.exact import ExactResult, solve_exact

__all__ = ["ExactResult", "solve_exact"]
