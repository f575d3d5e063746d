"""Grouped (segmented) regression: one least-squares model per soft group."""

from __future__ import annotations

from typing import Callable

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_array, check_is_fitted

from groupfit.errors import InputError
from groupfit.grouping import Constraints, hard_groups, serving_group_index, soft_groups
from groupfit.objective import OBJECTIVES, SegmentCost, grouped_residuals, residual_sum
from groupfit.search.exact import solve_exact
from groupfit.search.ga import GeneticSearch

SEARCHES = ("ga", "exact")
CERTIFY_PAIR_LIMIT = {"sse": 5_000_000, "sae": 200_000}
"""Largest number of segment pairs (≈ N²/2) for which a GA result is certified automatically."""


class GroupedRegressor(RegressorMixin, BaseEstimator):
    """Grouped multiple linear regression with optimised hard break points.

    The modelling run is split at ``p`` hard break points; each soft group
    (its hard group plus the ``n`` samples before it) gets its own
    least-squares coefficient vector. Breaks minimise Rg, the residual sum in
    which every sample is scored by the group that serves it
    (:mod:`groupfit.objective`).

    Parameters
    ----------
    p : int
        Number of hard break points (0: one global regression).
    n : int
        Soft offset: samples shared by neighbouring soft groups.
    c : float
        Spacing coefficient: every hard group has more than ``c·M`` samples,
        M the number of coefficients per group.
    objective : {"sae", "sse"}
        Sum of absolute (the paper's R) or of squared residuals.
    fit_intercept : bool
        Whether each group has a constant term (counted in M).
    search : {"ga", "exact"}
        Genetic algorithm (as in the paper) or dynamic programming (the
        certified optimum).
    population_size, max_generations, stall_generations : int
        GA settings (see :class:`groupfit.search.ga.GeneticSearch`).
    polish : bool
        Finish the GA with a local search.
    local_window : int
        GA: each child's best single-break shift within ± this many samples
        (0: off).
    union_crossover : bool
        GA: also mate by drawing breaks from the union of the parents' breaks.
    certify : {"auto", True, False}
        Also run the exact search after the GA and report the gap; "auto"
        does so when it is cheap.
    random_state : int or None
        Seed of the GA.
    fixed_breaks : list of int or None
        Use these hard breaks instead of searching (e.g. to refit a model
        with another input); they must increase and lie strictly between n
        and N. ``p`` is then ignored: the model has ``len(fixed_breaks)``
        breaks.

    Attributes
    ----------
    breaks_ : list of int
        Hard break points, 1-based, each the last sample of its hard group.
    hard_groups_, soft_groups_ : list of (int, int)
        1-based inclusive sample ranges.
    coef_ : ndarray, shape (n_groups, n_features)
        Temperature coefficients of each soft group.
    intercept_ : ndarray, shape (n_groups,)
        Constant terms (zeros without an intercept).
    objective_value_ : float
        Rg of the fitted model (µm for sae, µm² for sse).
    group_objective_ : ndarray, shape (n_groups,)
        Each group's share of Rg over the samples it serves.
    residuals_ : ndarray, shape (n_samples,)
        Training residuals ``y − ŷ``, each sample predicted by its serving group.
    search_ : dict
        How the breaks were found: method, seed, evaluations, seconds and,
        when certified, the exact optimum and the gap in percent.
    n_samples_fit_ : int
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        Present when X had column names.
    """

    def __init__(
        self,
        p: int = 1,
        n: int = 3,
        c: float = 3.0,
        objective: str = "sae",
        fit_intercept: bool = True,
        search: str = "ga",
        population_size: int = 60,
        max_generations: int = 300,
        stall_generations: int = 30,
        polish: bool = True,
        local_window: int = 5,
        union_crossover: bool = True,
        certify="auto",
        random_state: int | None = None,
        fixed_breaks: list[int] | None = None,
    ):
        self.p = p
        self.n = n
        self.c = c
        self.objective = objective
        self.fit_intercept = fit_intercept
        self.search = search
        self.population_size = population_size
        self.max_generations = max_generations
        self.stall_generations = stall_generations
        self.polish = polish
        self.local_window = local_window
        self.union_crossover = union_crossover
        self.certify = certify
        self.random_state = random_state
        self.fixed_breaks = fixed_breaks

    @property
    def n_coef(self) -> int:
        """M: coefficients per group, intercept included."""
        check_is_fitted(self, "n_features_in_")
        return self.n_features_in_ + int(self.fit_intercept)

    def fit(self, X, y, progress: Callable[[str, float], None] | None = None):
        """Find the hard breaks and fit every soft group.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Temperatures, one row per sample in time order.
        y : array-like, shape (n_samples,)
            Thermal error.
        progress : callable, optional
            ``progress(stage, fraction)`` for progress bars.
        """
        self._check_parameters()
        if hasattr(X, "columns"):
            self.feature_names_in_ = np.asarray([str(c) for c in X.columns], dtype=object)
        X = check_array(X, ensure_min_samples=2)
        y = check_array(y, ensure_2d=False, dtype=float).ravel()
        if len(y) != len(X):
            raise InputError(f"X has {len(X)} rows but y has {len(y)}")
        self.n_features_in_ = X.shape[1]
        n_samples = len(y)
        if self.fixed_breaks is not None:
            return self._fit_fixed(X, y)
        constraints = Constraints.for_model(n_samples, self.n, self.c, self.n_coef)
        constraints.require(self.p, self.c, self.n_coef)

        cost = SegmentCost(X, y, n=self.n, objective=self.objective, fit_intercept=self.fit_intercept)
        if self.search == "exact" or self.p == 0:
            exact = solve_exact(cost, constraints, self.p, progress=_stage(progress, "exact"))
            breaks, search_value = exact.breaks[self.p], exact.objective[self.p]
            info = {"method": "exact", "evaluations": exact.evaluations, "seconds": exact.seconds}
        else:
            ga = GeneticSearch(
                population_size=self.population_size,
                max_generations=self.max_generations,
                stall_generations=self.stall_generations,
                polish=self.polish,
                seed=self.random_state,
                local_window=self.local_window,
                union_crossover=self.union_crossover,
            )
            reporter = None
            if progress is not None:
                reporter = lambda generation, best: progress("ga", generation / self.max_generations)  # noqa: E731
            result = ga.run(cost, constraints, self.p, progress=reporter)
            breaks, search_value = result.breaks, result.objective
            info = {
                "method": "ga",
                "seed": self.random_state,
                "evaluations": result.evaluations,
                "segment_costs": result.segment_costs,
                "generations": result.generations,
                "stopped": result.stopped,
                "seconds": result.seconds,
            }
            if self._should_certify(n_samples):
                exact = solve_exact(cost, constraints, self.p, progress=_stage(progress, "exact"))
                best = exact.objective[self.p]
                info["exact_objective"] = best
                info["exact_breaks"] = exact.breaks[self.p]
                info["exact_seconds"] = exact.seconds
                info["gap_percent"] = 100.0 * (search_value - best) / best if best > 0 else 0.0
        info["search_objective"] = search_value
        return self._fit_groups(X, y, breaks, info)

    def _fit_fixed(self, X: np.ndarray, y: np.ndarray):
        breaks = [int(b) for b in self.fixed_breaks]
        n_samples = len(y)
        edges = [self.n, *breaks, n_samples]
        if any(b <= a for a, b in zip(edges[:-1], edges[1:])):
            raise InputError(
                f"fixed breaks {breaks} must increase and lie strictly between n = {self.n} and N = {n_samples}"
            )
        return self._fit_groups(X, y, breaks, {"method": "fixed", "seconds": 0.0})

    def _fit_groups(self, X: np.ndarray, y: np.ndarray, breaks, info: dict):
        n_samples = len(y)
        self.breaks_ = [int(b) for b in breaks]
        self.n_samples_fit_ = n_samples
        self.hard_groups_ = hard_groups(self.breaks_, n_samples)
        self.soft_groups_ = soft_groups(self.breaks_, n_samples, self.n)
        coefs, self.residuals_ = grouped_residuals(X, y, self.breaks_, n=self.n, fit_intercept=self.fit_intercept)
        coefs = np.asarray(coefs)
        if self.fit_intercept:
            self.intercept_, self.coef_ = coefs[:, 0], coefs[:, 1:]
        else:
            self.intercept_, self.coef_ = np.zeros(len(coefs)), coefs
        serving = serving_group_index(self.breaks_, n_samples, self.n)
        self.group_objective_ = np.array(
            [residual_sum(self.residuals_[serving == g], self.objective) for g in range(len(coefs))]
        )
        self.objective_value_ = float(self.group_objective_.sum())
        self.search_ = info
        from groupfit.inference.prediction import group_interval_stats

        self.interval_stats_ = group_interval_stats(X, y, self.soft_groups_, self.fit_intercept)
        return self

    def serving_groups(self, n_samples: int | None = None) -> np.ndarray:
        """0-based index of the group serving each sample (offline, by sample index)."""
        check_is_fitted(self, "breaks_")
        return serving_group_index(self.breaks_, self.n_samples_fit_, self.n, n_samples)

    def predict(self, X, return_interval: bool = False, level: float | None = None, alpha: float | None = None):
        """Predict the error of a run sampled like the modelling run, by sample index.

        Row i of X is served by the group that serves sample i of the
        modelling run (rows past its end by the last group). The run-time
        switching logic, which decides from live temperatures, is
        :mod:`groupfit.switching`.

        With ``return_interval=True`` returns ``(prediction, lower, upper)``:
        the serving group's OLS prediction interval at ``level`` (default
        0.95; or give ``alpha = 1 − level``), see
        :mod:`groupfit.inference.prediction`.
        """
        check_is_fitted(self, "breaks_")
        X = check_array(X)
        if X.shape[1] != self.n_features_in_:
            raise InputError(f"X has {X.shape[1]} temperature columns; the model was fitted on {self.n_features_in_}")
        group = self.serving_groups(len(X))
        prediction = self.intercept_[group] + np.einsum("ij,ij->i", X, self.coef_[group])
        if not return_interval:
            return prediction
        from groupfit.inference.prediction import estimator_bounds

        return (prediction, *estimator_bounds(self, X, group, prediction, level=level, alpha=alpha))

    def _check_parameters(self) -> None:
        if self.objective not in OBJECTIVES:
            raise InputError(f"objective {self.objective!r}: choose one of {', '.join(OBJECTIVES)}")
        if self.search not in SEARCHES:
            raise InputError(f"search {self.search!r}: choose one of {', '.join(SEARCHES)}")
        if int(self.p) != self.p or self.p < 0:
            raise InputError(f"p = {self.p!r}: the number of breaks must be a whole number ≥ 0")
        if int(self.n) != self.n or self.n < 0:
            raise InputError(f"n = {self.n!r}: the soft offset must be a whole number ≥ 0")
        if not np.isfinite(self.c) or self.c < 0:
            raise InputError(f"c = {self.c!r}: the spacing coefficient must be a finite number ≥ 0")

    def _should_certify(self, n_samples: int) -> bool:
        if self.certify == "auto":
            return n_samples * n_samples / 2 <= CERTIFY_PAIR_LIMIT[self.objective]
        return bool(self.certify)


def _stage(progress, stage: str):
    if progress is None:
        return None
    return lambda fraction: progress(stage, fraction)
