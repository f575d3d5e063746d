"""Genetic-algorithm break-point search (DEAP), as in the paper.

Encoding. A break vector ``b_1 < … < b_p`` with hard groups of at least
``min_size`` samples and ``lowest ≤ b_1``, ``b_p ≤ highest`` is stored as the gaps-free
vector ``u_j = b_j − (j−1)·min_size``. The constraints become simply
``lowest ≤ u_1 ≤ … ≤ u_p ≤ highest − (p−1)·min_size``, so *any* integer vector is made
feasible by clipping it to that interval and sorting it: every individual the
operators produce is repaired, never penalised.

Operators suited to ordered integer vectors: uniform crossover, an arithmetic
blend of the parents (then rounding), or children drawn from the union of the
parents' breaks; Gaussian integer shifts of single breaks with an occasional
uniform reset; tournament selection; and elitism (the best individuals pass
unchanged). Every child then takes its best single-break shift within a small
window (a Lamarckian step): Rg has narrow valleys around the changes of
operating condition, and the step lets the population sit in them. The run
stops when the best Rg has not improved for ``stall_generations`` generations.

Fitness is evaluated for the whole population at once: the distinct ``(a, b)``
segment pairs not yet seen are costed in one vectorised call and cached, since
break positions are "soft" and the population revisits the same segments.

With ``polish=True`` (the default) the best individual is finished by a local
search that moves one break at a time to its best position between its
neighbours, until no move improves Rg, as MATLAB's ``ga`` does with a hybrid
function (:mod:`groupfit.search.polish`).
"""

from __future__ import annotations

import contextlib
import random
import time as _time
from dataclasses import KW_ONLY, dataclass, field
from typing import Callable, Iterator

import numpy as np
from deap import base, tools

from groupfit import running
from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.base import GA_DEFAULTS, GASettings, SearchResult
from groupfit.search.polish import improves, polish_breaks, shift_range


@dataclass(kw_only=True)
class GAResult(SearchResult):
    """Outcome of one GA run (a :class:`~groupfit.search.base.SearchResult`).

    Attributes
    ----------
    evaluations : int
        Break vectors whose fitness was evaluated (population members and
        local-search candidates).
    segment_costs : int
        Distinct soft-group costs computed.
    generations : int
    stopped : str
        ``"stagnation"`` or ``"max_generations"``.
    history : list of float
        Best Rg after each generation.
    evaluations_history : list of int
        Evaluations made by the end of each generation.
    """

    method: str = "ga"
    segment_costs: int
    generations: int
    stopped: str
    history: list[float] = field(default_factory=list)
    evaluations_history: list[int] = field(default_factory=list)

    def details(self) -> dict:
        return {"segment_costs": self.segment_costs, "generations": self.generations, "stopped": self.stopped}


class BreakFitness(base.Fitness):
    weights = (-1.0,)


class Individual(list):
    """A break vector in gap-free coordinates, with its DEAP fitness."""

    def __init__(self, iterable=()):
        super().__init__(iterable)
        self.fitness = BreakFitness()


@contextlib.contextmanager
def seeded_random(seed: int | None) -> Iterator[None]:
    """Seed Python's ``random`` (which DEAP's tools draw from) and restore it afterwards."""
    state = random.getstate()
    random.seed(seed)
    try:
        yield
    finally:
        random.setstate(state)


class CachedObjective:
    """Rg of break vectors, with every segment cost computed once.

    Segment ``(a, b)`` is keyed ``a·(N+1) + b``; the cache is a sorted key
    array and its values, so a whole batch is looked up with one
    ``searchsorted`` and the missing segments are costed in one call.
    """

    def __init__(self, cost: SegmentCost):
        self.cost = cost
        self.keys = np.empty(0, dtype=np.int64)
        self.values = np.empty(0)
        self.evaluations = 0

    def totals(self, break_vectors) -> list[float]:
        """Rg of each break vector (all of the same length)."""
        if len(break_vectors) == 0:
            return []
        n_samples = self.cost.n_samples
        breaks = np.asarray(break_vectors, dtype=np.int64).reshape(len(break_vectors), -1)
        edges = np.hstack(
            [np.zeros((len(breaks), 1), dtype=np.int64), breaks, np.full((len(breaks), 1), n_samples, dtype=np.int64)]
        )
        keys = edges[:, :-1] * (n_samples + 1) + edges[:, 1:]
        unique = np.unique(keys)
        position = np.searchsorted(self.keys, unique)
        known = position < len(self.keys)
        known[known] = self.keys[position[known]] == unique[known]
        missing = unique[~known]
        if missing.size:
            costs = self.cost.pair_costs(missing // (n_samples + 1), missing % (n_samples + 1))
            merged = np.concatenate([self.keys, missing])
            order = np.argsort(merged, kind="stable")
            self.keys = merged[order]
            self.values = np.concatenate([self.values, costs])[order]
        self.evaluations += len(breaks)
        return self.values[np.searchsorted(self.keys, keys)].sum(axis=1).tolist()


class GapFreeEncoding:
    """Break vectors as gap-free coordinates ``u_j = b_j − (j−1)·min_size``.

    Feasible break vectors correspond one to one to non-decreasing integer
    vectors in ``[low, high]``; :meth:`repair` maps any real vector there.
    """

    def __init__(self, constraints: Constraints, p: int):
        self.p = p
        self.offsets = np.arange(p) * constraints.min_size
        self.low = constraints.lowest_break
        self.high = constraints.highest_break - (p - 1) * constraints.min_size

    def to_breaks(self, u) -> list[int]:
        return (np.asarray(u, dtype=np.int64) + self.offsets).tolist()

    def from_breaks(self, breaks) -> list[int]:
        return (np.asarray(breaks, dtype=np.int64) - self.offsets).tolist()

    def repair(self, individual: list) -> list:
        """Round, clip to ``[low, high]`` and sort, in place."""
        individual[:] = sorted(min(self.high, max(self.low, int(round(g)))) for g in individual)
        return individual


@dataclass
class Variation:
    """The GA's operators on one encoding: evaluation, crossover, mutation and the Lamarckian local step.

    They draw from :mod:`random`, seeded by the search (:func:`seeded_random`).
    """

    encoding: GapFreeEncoding
    constraints: Constraints
    objective: CachedObjective
    _: KW_ONLY
    union_crossover: bool
    sigma: float = field(init=False)
    """Standard deviation (gap-free coordinates) of the wide Gaussian mutation: a tenth of the range, at least 1."""

    def __post_init__(self) -> None:
        self.sigma = max(1.0, 0.1 * (self.encoding.high - self.encoding.low))

    @property
    def p(self) -> int:
        return self.encoding.p

    def evaluate(self, population: list[Individual]) -> None:
        to_breaks = self.encoding.to_breaks
        fresh = [ind for ind in population if not ind.fitness.valid]
        for ind, value in zip(fresh, self.objective.totals([to_breaks(ind) for ind in fresh])):
            ind.fitness.values = (value,)

    def mate(self, a: Individual, b: Individual) -> tuple[Individual, Individual]:
        encoding, p = self.encoding, self.p
        draw = random.random()
        if p > 1 and self.union_crossover and draw < 1 / 3:
            pool = sorted(set(encoding.to_breaks(a)) | set(encoding.to_breaks(b)))
            a[:] = encoding.from_breaks(sorted(random.sample(pool, p)))
            b[:] = encoding.from_breaks(sorted(random.sample(pool, p)))
        elif p > 1 and draw < 2 / 3:
            tools.cxUniform(a, b, indpb=0.5)
        else:
            weight = random.random()
            a[:], b[:] = (
                [weight * x + (1 - weight) * y for x, y in zip(a, b)],
                [(1 - weight) * x + weight * y for x, y in zip(a, b)],
            )
        return encoding.repair(a), encoding.repair(b)

    def mutate(self, ind: Individual) -> Individual:
        low, high = self.encoding.low, self.encoding.high
        gene = random.randrange(self.p)
        if random.random() < 0.15:
            ind[gene] = random.randint(low, high)
        else:
            scale = self.sigma if random.random() < 0.5 else 2.0
            ind[gene] = ind[gene] + random.gauss(0.0, scale)
        return self.encoding.repair(ind)

    def local_step(self, children: list[Individual], window: int) -> None:
        """One pass of windowed single-break shifts on every child (Lamarckian)."""
        offers = []
        for child in children:
            breaks = self.encoding.to_breaks(child)
            for j in range(self.p):
                first, last = shift_range(breaks, j, self.constraints)
                for b in range(max(first, breaks[j] - window), min(last, breaks[j] + window) + 1):
                    if b != breaks[j]:
                        offers.append((child, breaks[:j] + [b] + breaks[j + 1 :]))
        values = self.objective.totals([trial for _, trial in offers])
        best: dict[int, tuple[float, list[int]]] = {}
        for (child, trial), value in zip(offers, values):
            if value < best.get(id(child), (child.fitness.values[0], None))[0]:
                best[id(child)] = (value, trial)
        for child in children:
            if id(child) in best:
                value, trial = best[id(child)]
                child[:] = self.encoding.from_breaks(trial)
                child.fitness.values = (value,)


@dataclass
class GeneticSearch:
    """DEAP genetic algorithm over feasible break vectors.

    Parameters
    ----------
    population_size : int
    max_generations : int
    stall_generations : int
        Stop when the best Rg has not improved for this many generations.
    crossover_prob, mutation_prob : float
        Probabilities that a pair is mated and that a child is mutated.
    elite : int
        Individuals copied unchanged into the next generation.
    tournament_size : int
    polish : bool
        Finish with a local search (see :func:`polish_breaks`).
    seed : int or None
        Seed of the run; the same seed gives the same result.
    local_window : int
        Every child takes the best single-break shift within ``±local_window``
        samples before it joins the population (a Lamarckian step; 0: off).
    union_crossover : bool
        Also mate by drawing each child's breaks from the union of its
        parents' breaks, which keeps breaks that sit well as building blocks.
    """

    population_size: int = GA_DEFAULTS.population_size
    max_generations: int = GA_DEFAULTS.max_generations
    stall_generations: int = GA_DEFAULTS.stall_generations
    crossover_prob: float = 0.8
    mutation_prob: float = 0.4
    elite: int = 2
    tournament_size: int = 3
    _: KW_ONLY
    polish: bool = GA_DEFAULTS.polish
    seed: int | None = None
    local_window: int = GA_DEFAULTS.local_window
    union_crossover: bool = GA_DEFAULTS.union_crossover

    @classmethod
    def from_settings(cls, settings: GASettings, seed: int | None = None) -> "GeneticSearch":
        return cls(seed=seed, **settings.as_dict())

    def run(
        self,
        cost: SegmentCost,
        constraints: Constraints,
        p: int,
        progress: Callable[[int, float], None] | None = None,
    ) -> GAResult:
        """Search p breaks; ``progress(generation, best)`` is called after each generation."""
        start = _time.perf_counter()
        objective = CachedObjective(cost)
        costs_before = cost.evaluations
        if p == 0:
            value = objective.totals([[]])[0]
            return GAResult(
                breaks=[],
                objective=value,
                evaluations=1,
                segment_costs=cost.evaluations - costs_before,
                generations=0,
                seconds=_time.perf_counter() - start,
                stopped="trivial",
                history=[value],
                seed=self.seed,
            )

        encoding = GapFreeEncoding(constraints, p)
        low, high, repair = encoding.low, encoding.high, encoding.repair
        variation = Variation(encoding, constraints, objective, union_crossover=self.union_crossover)
        evaluate, mate, mutate = variation.evaluate, variation.mate, variation.mutate

        history: list[float] = []
        evaluations_history: list[int] = []
        with seeded_random(self.seed):
            population = [
                repair(Individual(random.randint(low, high) for _ in range(p))) for _ in range(self.population_size)
            ]
            evaluate(population)
            best = tools.selBest(population, 1)[0]
            best_value = best.fitness.values[0]
            stalled = 0
            stopped = "max_generations"
            generation = 0
            for generation in range(1, self.max_generations + 1):
                elite = [Individual(ind) for ind in tools.selBest(population, self.elite)]
                for source, copy in zip(tools.selBest(population, self.elite), elite):
                    copy.fitness.values = source.fitness.values
                parents = tools.selTournament(population, self.population_size - self.elite, self.tournament_size)
                children = [Individual(ind) for ind in parents]
                for a, b in zip(children[::2], children[1::2]):
                    if random.random() < self.crossover_prob:
                        mate(a, b)
                for child in children:
                    if random.random() < self.mutation_prob:
                        mutate(child)
                evaluate(children)
                if self.local_window:
                    variation.local_step(children, self.local_window)
                population = elite + children
                leader = tools.selBest(population, 1)[0]
                if improves(leader.fitness.values[0], best_value):
                    best, best_value, stalled = leader, leader.fitness.values[0], 0
                else:
                    stalled += 1
                history.append(best_value)
                evaluations_history.append(objective.evaluations)
                if progress is not None:
                    progress(generation, best_value)
                if stalled >= self.stall_generations:
                    stopped = "stagnation"
                    break

        breaks = encoding.to_breaks(best)
        if self.polish:
            with running.stage("ga polish", enabled=progress is not None):
                breaks, best_value = polish_breaks(breaks, best_value, objective, constraints)
        return GAResult(
            breaks=breaks,
            objective=best_value,
            evaluations=objective.evaluations,
            segment_costs=cost.evaluations - costs_before,
            generations=generation,
            seconds=_time.perf_counter() - start,
            stopped=stopped,
            history=history,
            evaluations_history=evaluations_history,
            seed=self.seed,
        )
