"""Grouped (segmented) regression: one least-squares model per soft group."""

from __future__ import annotations

import time
from typing import Any, Callable, Mapping

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_array, check_is_fitted, column_or_1d

from groupfit.errors import InputError
from groupfit.grouping import (
    DEFAULT_SOFT_OFFSET,
    DEFAULT_SPACING,
    Constraints,
    check_spacing,
    hard_groups,
    serving_group_index,
    shared_fit,
    shared_mask,
    soft_groups,
)
from groupfit.inference.prediction import estimator_bounds, group_interval_stats
from groupfit.metrics import error_metrics
from groupfit.model import ModelFile, Switching, grouped_prediction
from groupfit.models.ridge import check_ridge_alpha
from groupfit.objective import OBJECTIVES, SegmentCost, grouped_residuals, residual_sum
from groupfit.runtime.rule import rule_parameters, source_ranges
from groupfit.search.base import GA_DEFAULTS, METHODS, GASettings, SearchSettings
from groupfit.search.exact import CERTIFY_PAIR_LIMIT, exact_is_cheap, solve_exact
from groupfit.search.factory import make_search
from groupfit.search.progress import ga_reporter, stage_reporter

SEARCHES = METHODS
DEFAULT_SEARCH = SearchSettings()


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
    shared_columns : sequence of bool or None
        Inputs with one coefficient for every group (a diagnosis's effects, :mod:`groupfit.heldout.design`), fitted
        with each group's own on the hard groups, each soft group then refitted on what they leave; no intervals.

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

    Notes
    -----
    scikit-learn's ``check_estimator`` passes (tests/test_models.py) with
    ``c = 0``: its test data (10 to 50 samples) is too short for the default
    spacing c = 3, and an infeasible p is refused rather than quietly fitted
    with fewer breaks (no p = 0 fallback). With p ≥ 1 two checks are declared
    as expected failures through ``expected_failed_checks``: the sample-order
    and subset invariance of ``predict``, since row i is served by the group
    that serves sample i of the run (prediction follows the time order).
    """

    def __init__(
        self,
        p: int = 1,
        n: int = DEFAULT_SOFT_OFFSET,
        c: float = DEFAULT_SPACING,
        objective: str = "sae",
        *,
        fit_intercept: bool = True,
        search: str = "ga",
        population_size: int = GA_DEFAULTS.population_size,
        max_generations: int = GA_DEFAULTS.max_generations,
        stall_generations: int = GA_DEFAULTS.stall_generations,
        polish: bool = GA_DEFAULTS.polish,
        local_window: int = GA_DEFAULTS.local_window,
        union_crossover: bool = GA_DEFAULTS.union_crossover,
        certify="auto",
        random_state: int | None = None,
        fixed_breaks: list[int] | None = None,
        ridge_alpha: float = 0.0,
        shared_columns=None,
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
        self.ridge_alpha = ridge_alpha
        self.shared_columns = shared_columns

    @property
    def n_coef(self) -> int:
        """M: coefficients per group, intercept included."""
        check_is_fitted(self, "n_features_in_")
        return self.n_features_in_ + int(self.fit_intercept)

    @property
    def search_settings(self) -> SearchSettings:
        """The search among the parameters (the exact one for p = 0, where there is nothing to search)."""
        method = "exact" if self.p == 0 else self.search
        return SearchSettings(method=method, seed=self.random_state, ga=self.ga_settings, certify=self.certify)

    @property
    def ga_settings(self) -> GASettings:
        """The GA settings among the parameters."""
        return GASettings(**{name: getattr(self, name) for name in GA_DEFAULTS.as_dict()})

    @classmethod
    def from_settings(
        cls,
        *,
        p: int,
        n: int = DEFAULT_SOFT_OFFSET,
        c: float = DEFAULT_SPACING,
        objective: str = "sae",
        fit_intercept: bool = True,
        search: SearchSettings = DEFAULT_SEARCH,
    ) -> "GroupedRegressor":
        """The estimator of a model and search setting: the one path from settings to an estimator."""
        return cls(
            p=p,
            n=n,
            c=float(c),
            objective=objective,
            fit_intercept=fit_intercept,
            search=search.method,
            certify=search.certify,
            random_state=search.seed,
            **search.ga.as_dict(),
        )

    @classmethod
    def from_config(cls, config: Mapping[str, Mapping[str, Any]], **search_changes) -> "GroupedRegressor":
        """The estimator of a sweep's run specification (:mod:`groupfit.sweep.config`): its ``model`` and ``search``.

        ``search_changes``
        override :class:`~groupfit.search.base.SearchSettings` fields (e.g. ``certify=False``).
        """
        model = config["model"]
        return cls.from_settings(
            p=model["p"],
            n=model["n"],
            c=model["c"],
            objective=model["objective"],
            fit_intercept=model["intercept"],
            search=SearchSettings.from_mapping(config["search"]).replace(**search_changes),
        )

    def fit(self, X, y, progress: Callable[[str, float], None] | None = None):
        """Find the hard breaks and fit every soft group.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            The model's inputs (temperature readings, derived inputs), one row per sample in time order.
        y : array-like, shape (n_samples,)
            Thermal error.
        progress : callable, optional
            ``progress(stage, fraction)`` for progress bars.
        """
        self._check_parameters()
        if hasattr(X, "columns"):
            self.feature_names_in_ = np.asarray([str(c) for c in X.columns], dtype=object)
        if y is None:
            raise ValueError(f"{type(self).__name__} requires y to be passed, but the target y is None")
        X = check_array(X, ensure_min_samples=2)
        y = column_or_1d(check_array(y, ensure_2d=False, dtype=float), warn=True)
        if len(y) != len(X):
            raise InputError(f"X has {len(X)} rows but y has {len(y)}")
        self.n_features_in_ = X.shape[1]
        n_samples = len(y)
        if self.fixed_breaks is not None:
            return self._fit_fixed(X, y)
        constraints = Constraints.for_model(n_samples, self.n, self.c, self.n_coef)
        constraints.require(self.p, self.c, self.n_coef)
        if self.p == 0:  # one least-squares fit: no breaks to search, no table of segment sums
            started = time.perf_counter()
            self._fit_groups(X, y, [], {"method": "exact", "seed": None, "evaluations": 1})
            self.search_.update(seconds=time.perf_counter() - started, search_objective=self.objective_value_)
            return self

        cost = SegmentCost(X, y, n=self.n, objective=self.objective, fit_intercept=self.fit_intercept)
        settings = self.search_settings
        if settings.method == "exact":
            reporter = stage_reporter(progress, "exact")
        else:
            reporter = None if progress is None else ga_reporter(progress, self.max_generations, self.stall_generations)
        result = make_search(settings).run(cost, constraints, self.p, progress=reporter)
        if settings.method == "ga" and progress is not None:
            progress("ga", 1.0)
        breaks, search_value, info = result.breaks, result.objective, result.info()
        if result.method == "ga":
            if self._should_certify(n_samples):
                exact = solve_exact(
                    cost,
                    constraints,
                    self.p,
                    progress=stage_reporter(progress, "exact"),
                    incumbents={self.p: breaks},
                    every_p=False,
                )
                best = exact.objective[self.p]
                info["exact_objective"] = best
                info["exact_breaks"] = exact.breaks[self.p]
                info["exact_seconds"] = exact.seconds
                info["gap_percent"] = 100.0 * (search_value - best) / best if best > 0 else 0.0
            else:
                info["exact_skipped"] = self._certify_skipped(n_samples)
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
        serving = serving_group_index(self.breaks_, n_samples, self.n)
        shared = shared_mask(self.shared_columns, X.shape[1], self.breaks_)
        own, own_y, gamma = shared_fit(X, y, serving, len(self.breaks_) + 1, shared, intercept=self.fit_intercept)
        coefs, self.residuals_ = grouped_residuals(
            own, own_y, self.breaks_, n=self.n, fit_intercept=self.fit_intercept, ridge_alpha=float(self.ridge_alpha)
        )
        coefs = np.asarray(coefs)
        self.intercept_, slopes = (coefs[:, 0], coefs[:, 1:]) if self.fit_intercept else (np.zeros(len(coefs)), coefs)
        self.coef_ = slopes
        if gamma is not None:
            self.coef_ = np.empty((len(coefs), X.shape[1]))
            self.coef_[:, ~shared], self.coef_[:, shared] = slopes, gamma
        self.group_objective_ = np.array(
            [residual_sum(self.residuals_[serving == g], self.objective) for g in range(len(coefs))]
        )
        self.objective_value_ = float(self.group_objective_.sum())
        self.search_ = info
        self.interval_stats_ = None
        if not float(self.ridge_alpha) > 0 and gamma is None:
            self.interval_stats_ = group_interval_stats(X, y, self.soft_groups_, fit_intercept=self.fit_intercept)
        return self

    def serving_groups(self, n_samples: int | None = None) -> np.ndarray:
        """0-based index of the group serving each sample (offline, by sample index)."""
        check_is_fitted(self, "breaks_")
        return serving_group_index(self.breaks_, self.n_samples_fit_, self.n, n_samples)

    def predict(self, X, *, return_interval: bool = False, level: float | None = None, alpha: float | None = None):
        """Predict the error of a run sampled like the modelling run, by sample index.

        Row i of X is served by the group that serves sample i of the
        modelling run (rows past its end by the last group). The run-time
        switching logic, which decides from live temperatures, is
        :mod:`groupfit.runtime`.

        With ``return_interval=True`` returns ``(prediction, lower, upper)``:
        the serving group's OLS prediction interval at ``level`` (default
        0.95; or give ``alpha = 1 − level``), see
        :mod:`groupfit.inference.prediction`.
        """
        check_is_fitted(self, "breaks_")
        X = check_array(X)
        if X.shape[1] != self.n_features_in_:
            raise InputError(
                f"X has {X.shape[1]} features, but {type(self).__name__} is expecting {self.n_features_in_} "
                "features as input (one per model input)"
            )
        group = self.serving_groups(len(X))
        prediction = grouped_prediction(self.intercept_, self.coef_, X, group)
        if not return_interval:
            return prediction
        return (prediction, *estimator_bounds(self, X, group, prediction, level=level, alpha=alpha))

    def to_model_file(self, run, criterion: str | None = None) -> ModelFile:
        """The model file of this model, fitted on ``run`` (a :class:`groupfit.data.Run`).

        ``criterion``: the switching criterion sensor (default: the input that
        moves most over the run, :func:`default_criterion`).
        """
        check_is_fitted(self, "breaks_")
        criterion = criterion or default_criterion(run)
        if criterion not in run.temp_names:
            raise InputError(
                f"switching criterion '{criterion}' is not a model input; choose one of {', '.join(run.temp_names)}"
            )
        column = run.temp_names.index(criterion)
        coefficients = [
            ([float(b0)] if self.fit_intercept else []) + [float(v) for v in slopes]
            for b0, slopes in zip(self.intercept_, self.coef_)
        ]
        metrics = error_metrics(self.residuals_)
        metrics["sse_um2"] = float(np.sum(self.residuals_**2))
        switching = Switching(
            criterion=criterion,
            criterion_index=column,
            criterion_series=tuple(float(v) for v in run.temps[:, column]),
        )
        model = ModelFile(
            sampling_period_s=float(run.period),
            temps=tuple(run.temp_names),
            error=run.error_name,
            intercept=bool(self.fit_intercept),
            objective=self.objective,
            p=len(self.breaks_),
            n=int(self.n),
            c=float(self.c),
            n_samples=int(self.n_samples_fit_),
            breaks=tuple(self.breaks_),
            hard_groups=tuple(tuple(g) for g in self.hard_groups_),
            soft_groups=tuple(tuple(g) for g in self.soft_groups_),
            coefficients=tuple(tuple(row) for row in coefficients),
            objective_value=float(self.objective_value_),
            group_objective=tuple(float(v) for v in self.group_objective_),
            switching=switching,
            training={"run": run.name, "time": run.time_name, **metrics},
            reference=getattr(run, "reference", None),
            ridge_alpha=float(self.ridge_alpha) if self.ridge_alpha else None,
        )
        rule = rule_parameters(model, run.temps, criterion_index=column, valid_readings=_raw_readings(run))
        ranges = source_ranges(run.frame, exclude=(run.time_name, run.error_name))
        switching = switching.with_rule(rule)
        return model.replace(switching=switching.with_rule({"source_ranges": ranges}))

    @classmethod
    def for_model_file(cls, model: ModelFile | Mapping[str, Any], **params) -> "GroupedRegressor":
        """An unfitted estimator with the model file's settings and ``params``."""
        model = ModelFile.coerce(model)
        settings = dict(p=model.p, n=model.n, c=model.c, objective=model.objective, fit_intercept=model.intercept)
        return cls(**settings, ridge_alpha=model.ridge_alpha or 0.0, **params)

    @classmethod
    def from_model_file(cls, model: ModelFile | Mapping[str, Any]) -> "GroupedRegressor":
        """A fitted estimator with the model file's groups and coefficients (no residuals or search details)."""
        model = ModelFile.coerce(model)
        estimator = cls.for_model_file(model)
        coefficients = np.asarray(model.coefficients, dtype=float)
        n_samples = model.n_samples_fit
        estimator.breaks_ = [int(b) for b in model.breaks]
        estimator.n_samples_fit_ = n_samples
        estimator.hard_groups_ = hard_groups(estimator.breaks_, n_samples)
        estimator.soft_groups_ = soft_groups(estimator.breaks_, n_samples, model.n)
        if model.intercept:
            estimator.intercept_, estimator.coef_ = coefficients[:, 0], coefficients[:, 1:]
        else:
            estimator.intercept_, estimator.coef_ = np.zeros(len(coefficients)), coefficients
        estimator.n_features_in_ = len(model.temps)
        estimator.feature_names_in_ = np.asarray(model.temps, dtype=object)
        estimator.objective_value_ = float(model.objective_value)
        return estimator

    def _check_parameters(self) -> None:
        if self.objective not in OBJECTIVES:
            raise InputError(f"objective {self.objective!r}: choose one of {', '.join(OBJECTIVES)}")
        if self.search not in SEARCHES:
            raise InputError(f"search {self.search!r}: choose one of {', '.join(SEARCHES)}")
        if int(self.p) != self.p or self.p < 0:
            raise InputError(f"p = {self.p!r}: the number of breaks must be a whole number ≥ 0")
        check_spacing(self.n, self.c)
        if check_ridge_alpha(self.ridge_alpha) > 0 and (self.p != 0 or self.fixed_breaks):
            raise InputError(
                f"ridge alpha {self.ridge_alpha:g} with p = {self.p}: the ridge penalty is for one global model "
                "(p = 0) on many collinear inputs; a grouped model's groups are fitted by least squares"
            )

    def _certify_skipped(self, n_samples: int) -> str:
        """Why a GA result was not checked against the exact optimum."""
        if self.certify != "auto":
            return "the check is turned off"
        limit = CERTIFY_PAIR_LIMIT[self.objective]
        return (
            f"N = {n_samples} samples give {n_samples * n_samples / 2:.3g} segment pairs, over the {limit:.3g} "
            f"of an automatic check with the {self.objective} objective; --certify yes runs it, --search exact "
            "finds the optimum itself"
        )

    def _should_certify(self, n_samples: int) -> bool:
        if self.certify == "auto":
            return exact_is_cheap(n_samples, self.objective)
        return bool(self.certify)


def _raw_readings(run) -> np.ndarray:
    """The run's input sensors as recorded (the valid ranges of a model with a reference temperature)."""
    if getattr(run, "reference", None) is None:
        return run.temps
    raw = np.array(run.temps, dtype=float)
    for j, name in enumerate(run.temp_names):
        if name in run.frame.columns:  # a measured input; a derived one is as computed
            raw[:, j] = run.frame[name].to_numpy(dtype=float)
    return raw


def default_criterion(run) -> str:
    """The input that moves most over the run: the clearest record of the thermal state."""
    spans = np.ptp(run.temps, axis=0)
    return run.temp_names[int(np.argmax(spans))]
