"""What every break search shares: its settings and the form of its result.

Imports neither DEAP nor scikit-learn, so configuration code, the sweep's
specifications and the command line can name the settings cheaply.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Mapping

METHODS = ("ga", "exact")


DEFAULT_SEED = 0
"""The seed every search, bootstrap and simulation uses unless told otherwise."""


@dataclass(frozen=True)
class GASettings:
    """Settings of the genetic algorithm (:class:`groupfit.search.ga.GeneticSearch`); the defaults live here only.

    Attributes
    ----------
    population_size, max_generations : int
    stall_generations : int
        Stop when the best Rg has not improved for this many generations.
    polish : bool
        Finish with a local search.
    local_window : int
        Each child's best single-break shift within ± this many samples (0: off).
    union_crossover : bool
        Also mate by drawing breaks from the union of the parents' breaks.
    """

    population_size: int = 60
    max_generations: int = 300
    stall_generations: int = 30
    polish: bool = True
    local_window: int = 5
    union_crossover: bool = True

    @classmethod
    def from_mapping(cls, table: Mapping[str, Any]) -> "GASettings":
        """The settings named in a table (a configuration's ``[search]``); the others keep their defaults."""
        names = {f.name for f in dataclasses.fields(cls)}
        return cls(**{key: value for key, value in table.items() if key in names})

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


GA_DEFAULTS = GASettings()


@dataclass(frozen=True)
class SearchSettings:
    """How the breaks are searched: method, seed, GA settings and whether a GA result is certified.

    ``certify``: ``"auto"`` (run the exact search after the GA when that is
    cheap), True or False.
    """

    method: str = "ga"
    seed: int | None = DEFAULT_SEED
    ga: GASettings = GA_DEFAULTS
    certify: Any = "auto"

    @classmethod
    def from_mapping(cls, table: Mapping[str, Any]) -> "SearchSettings":
        """From a configuration's ``[search]`` table or a sweep specification's ``search``."""
        return cls(
            method=table.get("method", cls.method),
            seed=table.get("seed", cls.seed),
            ga=GASettings.from_mapping(table),
            certify=table.get("certify", cls.certify),
        )

    def replace(self, **changes) -> "SearchSettings":
        return dataclasses.replace(self, **changes)


@dataclass(kw_only=True)
class SearchResult:
    """The breaks a search found for one p, and what it cost.

    Both searches answer in this form (:meth:`groupfit.search.exact.ExactResult.for_p`,
    :class:`groupfit.search.ga.GAResult`); :meth:`info` is what a fitted
    model keeps as ``search_``.
    """

    method: str
    breaks: list[int]
    objective: float
    """Rg of ``breaks``."""
    evaluations: int
    seconds: float
    seed: int | None = None

    def details(self) -> dict[str, Any]:
        """Method-specific numbers, for :meth:`info`."""
        return {}

    def info(self) -> dict[str, Any]:
        """``method``, ``seed`` (GA; null for a search that draws nothing), ``evaluations``, the method's
        details, ``seconds``."""
        head: dict[str, Any] = {"method": self.method, "seed": self.seed if self.method == "ga" else None}
        return {**head, "evaluations": self.evaluations, **self.details(), "seconds": self.seconds}


__all__ = ["GASettings", "GA_DEFAULTS", "METHODS", "SearchResult", "SearchSettings"]
