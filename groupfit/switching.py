"""Compatibility: the run-time rule now lives in :mod:`groupfit.runtime`; import from there."""

from groupfit.model import rule_section_problem
from groupfit.runtime import *  # noqa: F403
from groupfit.runtime import __all__ as _runtime_all

__all__ = [*_runtime_all, "rule_section_problem"]
