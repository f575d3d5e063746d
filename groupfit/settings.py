"""The typed settings of a run: one frozen object per table of a run configuration, each default written once.

A TOML configuration (:func:`groupfit.config.read_config`) and the command
line both end here: the configuration is read into a :class:`RunSettings`,
and the options a command was given replace fields with :meth:`RunSettings.given`
(an option not given, ``None``, leaves the field as it is). The estimators
take the tables they need (:meth:`groupfit.models.grouped.GroupedRegressor.from_settings`,
:class:`groupfit.comparison.ComparisonSettings`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Mapping

from groupfit.default_columns import DEFAULT_ERROR, DEFAULT_TIME
from groupfit.grouping import DEFAULT_SOFT_OFFSET, DEFAULT_SPACING
from groupfit.search.base import GASettings, SearchSettings


@dataclass(frozen=True, kw_only=True)
class DataSettings:
    """``[data]``: the runs and their columns (:mod:`groupfit.config` documents every key)."""

    path: str | tuple[str, ...] | None = None
    time: str = DEFAULT_TIME
    temps: tuple[str, ...] | None = None
    error: str = DEFAULT_ERROR
    validate: tuple[str, ...] = ()
    temp_range: tuple[float, float] | None = None
    error_limit: float | None = None
    period_tolerance: float | None = None
    resample_s: float | None = None
    ambient: str | None = None
    keep_glitches: bool = False
    encoding: str | None = None

    @property
    def paths(self) -> tuple[str, ...]:
        """The modelling runs named, as a tuple (empty when none)."""
        if not self.path:
            return ()
        return tuple(self.path) if isinstance(self.path, (list, tuple)) else (self.path,)


NEXT_RUN = "next-run"
P_RULES = (NEXT_RUN, "bic", "target")
"""How p is chosen: the expected next-run error (one-standard-error rule), BIC (in sample), or a target R."""


@dataclass(frozen=True, kw_only=True)
class ModelSettings:
    """``[model]``: the grouped model and how p is chosen."""

    p: int | str = "auto"
    pmax: int = 3
    p_rule: str = NEXT_RUN
    p_target: str | int | float | None = None
    n: int = DEFAULT_SOFT_OFFSET
    c: float = DEFAULT_SPACING
    objective: str = "sae"
    intercept: bool = True
    criterion: str | None = None
    reference: str | None = None


AR1_SCALINGS = ("heat_law", "rise")
"""How the AR(1) model (:class:`groupfit.models.ar1.AR1Model`) gets C2 of a level its modelling run did not have."""
AR1_FIT_METHODS = ("one_step", "free_run")
AR1_STARTS = ("measured", "zero")


@dataclass(frozen=True, kw_only=True)
class CompareSettings:
    """``[compare]``: what ``groupfit compare`` sets beside the grouped models."""

    pmax: int = 4
    heat: str | None = "speed_rpm"
    ar1_scaling: str = "heat_law"
    ar1_start: str = "measured"
    ar1_fit: str = "one_step"
    heat_exponent: float = 5 / 3
    rise_sensor: str | None = None
    rise_window_s: float = 6000.0
    structural_sensor: str | None = None
    structural_gain_um_per_K: float | None = None
    conditions: tuple[str, ...] = ("speed_rpm",)
    p_target: str | int | float | None = "20%"


SEARCH_KEYS = ("method", "seed", "certify")
"""The ``[search]`` keys of :class:`SearchSettings` itself; the others are :class:`GASettings` fields."""


@dataclass(frozen=True, kw_only=True)
class RunSettings:
    """A run configuration: ``[data]``, ``[model]``, ``[search]``, ``[output] dir`` and ``[compare]``."""

    data: DataSettings = field(default_factory=DataSettings)
    model: ModelSettings = field(default_factory=ModelSettings)
    search: SearchSettings = field(default_factory=SearchSettings)
    output_dir: str = "groupfit-out"
    compare: CompareSettings = field(default_factory=CompareSettings)

    @classmethod
    def from_tables(cls, tables: Mapping[str, Mapping[str, Any]]) -> "RunSettings":
        """From checked configuration tables (:func:`groupfit.config.check_config`); a missing key keeps its default."""
        return cls().given(**tables)

    def given(self, **tables: Mapping[str, Any]) -> "RunSettings":
        """These settings with the values of ``tables`` (``data={"time": "t"}``, …) that are not None."""
        changes: dict[str, Any] = {}
        for name, values in tables.items():
            values = {key: _frozen(value) for key, value in values.items() if value is not None}
            if not values:
                continue
            if name == "output":
                changes["output_dir"] = values.get("dir", self.output_dir)
            elif name == "search":
                changes["search"] = _search_given(self.search, values)
            else:
                changes[name] = dataclasses.replace(getattr(self, name), **values)
        return dataclasses.replace(self, **changes)

    def without_default_runs(self) -> "RunSettings":
        """The settings for a run named on the command line: no configured inputs or validation runs."""
        return dataclasses.replace(self, data=dataclasses.replace(self.data, temps=None, validate=()))


def _search_given(search: SearchSettings, values: Mapping[str, Any]) -> SearchSettings:
    ga = {key: value for key, value in values.items() if key not in SEARCH_KEYS}
    own = {key: value for key, value in values.items() if key in SEARCH_KEYS}
    return search.replace(ga=dataclasses.replace(search.ga, **ga) if ga else search.ga, **own)


def _frozen(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


__all__ = ["CompareSettings", "DataSettings", "GASettings", "ModelSettings", "RunSettings", "SearchSettings"]
