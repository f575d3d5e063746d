"""Grouped models against the global MLR and the physics AR(1) model, on several runs.

All models are fitted on the modelling run only; validation runs are
predicted without any refitting or tuning:

* MLR: the global regression's coefficients on each run's temperatures;
* AR(1): a free run from the run's first measured error (``ar1_start =
  "measured"``) or from 0 (``"zero"``, the paper's ΔL(0) = 0), C2 of unseen
  heat levels scaled by the heat law or the early-rise ratio;
* grouped p = 1…P: on the modelling run each sample is served by its group
  (by sample index); on other runs the run-time switching rule
  (:mod:`groupfit.runtime`) chooses the group from the live criterion
  temperature when it is available, else the groups are applied by sample
  index, and the table says which;
* fit's model: when the p ``fit`` would choose is 0 and ``fit`` writes
  another model than the MLR (a ridge penalty, a fast-response stage), that
  model, replayed by its run-time rule on every run
  (:mod:`groupfit.comparison_fit`).

A validation run is read as ``replay`` reads a next run: a reading that is
not a number, or outside its valid range (a sensor's fault code), is held,
then a sensor fault of the rule, and those samples are not scored
(:mod:`groupfit.comparison_faults`); the AR(1) model's state is held where
its heat reading is missed, as its routine holds it.

A modelling run whose error is measured on some rows only (a probe cycle
every few minutes) gets the global models only: MLR fitted on its measured
rows (grouped models' breaks are row indices of a complete error, the AR(1)
recursion needs the error on consecutive rows). Every run is scored on its
measured rows.
"""

from __future__ import annotations

from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from typing import Any, Callable, ContextManager, Mapping, Sequence

import numpy as np
import pandas as pd

from groupfit.clamped_scores import clamped
from groupfit.columns import input_order
from groupfit.comparison_ar1 import ar1_left_out_reason, expect_compared_ar1, fit_ar1, held_heat_notes, rise_notes
from groupfit.comparison_faults import replayed_on_faults
from groupfit.comparison_fit import FIT_KEY, differs_from_mlr, fit_model_file, fit_model_summary
from groupfit.comparison_path import grouped_path
from groupfit.comparison_runs import FittedModels, modelling_predictions, scored_rows, validation_predictions
from groupfit.comparison_runs import distance_to_change as distance_to_change
from groupfit.comparison_text import comparison_summary
from groupfit.conditions import condition_changes, run_condition
from groupfit.data import Run, join_runs, measured_rows
from groupfit.errors import InputError
from groupfit.heldout.expect import NextRunExpectation, expect_next_run
from groupfit.heldout.penalty import penalised_expectation
from groupfit.inference import break_intervals
from groupfit.inference.cli import AUTO_BUDGET_S
from groupfit.model import ModelFile
from groupfit.models.mlr import MLR
from groupfit.models.select_p import choose_p
from groupfit.runtime.rule import compensation_clamp
from groupfit.search.base import SearchSettings
from groupfit.settings import CompareSettings, ModelSettings, RunSettings


@dataclass
class ComparisonSettings:
    """What ``groupfit compare`` needs beyond the data: the ``[compare]`` table."""

    pmax: int = CompareSettings.pmax
    n: int = ModelSettings.n
    c: float = ModelSettings.c
    objective: str = ModelSettings.objective
    fit_intercept: bool = ModelSettings.intercept
    heat: str | None = CompareSettings.heat
    """The AR(1) model's heat-level column; None leaves the AR(1) model out (a run without one)."""
    ar1_scaling: str = CompareSettings.ar1_scaling
    ar1_start: str = CompareSettings.ar1_start
    """Where each AR(1) free run starts: the run's first measured error, or 0 (``"zero"``)."""
    ar1_fit: str = CompareSettings.ar1_fit
    """How the AR(1) model is fitted: on the one-step equations, or on the free-run error (``"free_run"``)."""
    heat_exponent: float = CompareSettings.heat_exponent
    rise_sensor: str | None = CompareSettings.rise_sensor
    rise_window_s: float = CompareSettings.rise_window_s
    structural_sensor: str | None = CompareSettings.structural_sensor
    structural_gain_um_per_K: float | None = CompareSettings.structural_gain_um_per_K
    conditions: tuple[str, ...] = CompareSettings.conditions
    p_target: str | float | None = CompareSettings.p_target
    fit_pmax: int = ModelSettings.pmax  # the largest p ``groupfit fit`` chooses among: compare marks its choice
    same_condition_samples: int = 2
    """A run is on the modelling run's condition when its condition columns go through the same levels in
    the same order, each change within this many samples of the modelling run's (:mod:`groupfit.conditions`)."""
    search: SearchSettings = SearchSettings()
    """Seed and GA settings of the grouped models (always the GA, never certified one by one)."""
    certify_path: bool = True
    """The path of R against p by the exact search; False: the GA's models alone (a run over the budget)."""
    intervals: dict[str, Any] = field(default_factory=dict)
    """Break-interval options (:func:`groupfit.inference.break_intervals` keywords: method, level, …)."""

    @classmethod
    def from_settings(cls, settings: RunSettings) -> "ComparisonSettings":
        """The ``[model]``, ``[search]`` and ``[compare]`` tables of a run configuration."""
        model, table = settings.model, settings.compare
        return cls(
            pmax=table.pmax,
            n=model.n,
            c=float(model.c),
            objective=model.objective,
            fit_intercept=model.intercept,
            heat=None if table.heat in (None, "none") else table.heat,
            ar1_scaling=table.ar1_scaling,
            ar1_start=table.ar1_start,
            ar1_fit=table.ar1_fit,
            heat_exponent=float(table.heat_exponent),
            rise_sensor=table.rise_sensor,
            rise_window_s=float(table.rise_window_s),
            structural_sensor=table.structural_sensor,
            structural_gain_um_per_K=table.structural_gain_um_per_K,
            conditions=tuple(table.conditions),
            p_target=table.p_target,
            fit_pmax=model.pmax,
            search=settings.search,
        )


@dataclass
class ComparisonResult:
    runs: list[str]
    rows: list[dict[str, Any]]
    predictions: dict[str, dict[str, np.ndarray]]
    path: dict[str, Any]
    selection: dict[str, Any]
    mlr_statistics: dict[str, Any]
    ar1: dict[str, Any] | None
    """The AR(1) model's coefficients; None when it was left out (``--heat none``)."""
    break_stability: list[dict[str, Any]]
    condition_changes: list[int]
    grouped_models: dict[int, ModelFile] = field(default_factory=dict)
    validation_rule: str = "sample index"
    break_intervals: dict[int, Any] = field(default_factory=dict)
    """Per p, a :class:`groupfit.inference.BreakIntervalReport` of the grouped model's breaks."""
    bands: dict[str, dict[str, tuple]] = field(default_factory=dict)
    """Per run and model key, the (lower, upper) prediction band of MLR and grouped models."""
    run_conditions: dict[str, str] = field(default_factory=dict)
    """Per run: ``"modelling"``, ``"same condition"`` or ``"other condition"`` (:mod:`groupfit.conditions`)."""
    reference: str | None = None
    """What the temperature inputs were taken relative to (:mod:`groupfit.reference`)."""
    expectation: NextRunExpectation | None = None
    """The expected next-run error of p = 0…pmax (:mod:`groupfit.heldout.expect`); ``fit_choice``: fit's p."""
    fit_choice: int | None = None
    fit_penalty: dict[str, Any] | None = None
    """The ridge penalty fit gives its choice of p = 0 (:func:`groupfit.heldout.penalty.penalised_expectation`)."""
    fit_model: ModelFile | None = None
    """The global model fit would write, when it is another than the MLR (a ridge penalty, a fast-response
    stage): scored on every run as replay scores it, in the rows ``"model": "fit"`` (:mod:`groupfit.comparison_fit`)."""
    notes: list[str] = field(default_factory=list)
    """What was left out and why (a modelling run whose error is not measured on every row, several runs)."""
    ar1_left_out: str | None = None
    """Why the AR(1) model was left out, when not for want of a heat-level column."""
    ar1_expectation: NextRunExpectation | None = None
    """The AR(1) model's expected next-run error (:func:`expect_compared_ar1`)."""

    def to_json(self) -> dict[str, Any]:
        """The machine-readable result (``compare --json``)."""
        return {
            "runs": self.runs,
            "rows": self.rows,
            "p_selection": self.selection,
            "exact_path": {
                **{k: self.path[k] for k in ("breaks", "objective", "R", "rss")},
                "certified": self.path.get("certified", True),
            },
            "break_stability": self.break_stability,
            "condition_changes": self.condition_changes,
            "mlr_statistics": self.mlr_statistics,
            "ar1": self.ar1,
            "validation_grouping": self.validation_rule,
            "break_intervals": {str(p): report.to_json() for p, report in self.break_intervals.items()},
            "run_conditions": self.run_conditions,
            "reference": self.reference,
            "notes": self.notes,
            "fit_model": self.fit_model and fit_model_summary(self.fit_model),
            "expected_next_run": self.expectation
            and {
                **self.expectation.to_json(),
                "fit_would_choose_p": self.fit_choice,
                "fit_would_choose_ridge": self.fit_penalty,
                "ar1": self.ar1_expectation
                and {**self.ar1_expectation.training(), "notes": list(self.ar1_expectation.notes)},
            },
        }

    def summary(self) -> str:
        """The comparison table and its notes, as ``groupfit compare`` prints them."""
        return comparison_summary(self)


def break_stability(path_breaks: list[list[int]]) -> list[dict[str, Any]]:
    """How far the breaks of p move when one more break is allowed (p → p+1)."""
    rows = []
    for p in range(1, len(path_breaks) - 1):
        current, following = path_breaks[p], path_breaks[p + 1]
        shifts = [min(abs(b - f) for f in following) for b in current]
        rows.append({"from_p": p, "to_p": p + 1, "max_shift": int(max(shifts)), "shifts": shifts})
    return rows


def in_modelling_order(modelling: Run, run: Run) -> Run:
    """``run`` with its inputs in the modelling run's order (a log may write its columns in another)."""
    order = input_order(modelling.temp_names, run.temp_names, run.source)
    return replace(run, temps=run.temps[:, order], temp_names=modelling.temp_names)


def compare_models(
    modelling: Run | Sequence[Run],
    validation: list[Run],
    settings: ComparisonSettings,
    live_rule: Callable[[ModelFile, np.ndarray], np.ndarray] | None = None,
    progress: Callable[[str, float], None] | None = None,
    *,
    recordings: Mapping[str, Run] | None = None,
    stage: Callable[[str], ContextManager] = lambda name: nullcontext(),
) -> ComparisonResult:
    """Fit every model on ``modelling`` and score it on every run.

    Parameters
    ----------
    modelling : Run or sequence of Run
        The modelling run; several runs are joined (:func:`groupfit.data.join_runs`)
        and get the global models only, their next-run expectation leaving one
        run out (:func:`joined_run_notes`).
    validation : list of Run
        The validation runs. A reading that is not a number, or outside its
        valid range, is a sensor fault of the run-time rule, as ``replay``
        reads it: held, then not scored (:mod:`groupfit.comparison_faults`).
        A missed heat reading of the AR(1) model holds its routine's state,
        as ``replay`` of an AR(1) model file holds it
        (:func:`groupfit.comparison_ar1.held_heat_notes`).
    live_rule : callable, optional
        ``live_rule(model, inputs) -> group index per sample (0-based)``;
        when given, grouped models serve validation runs through it.
    recordings : mapping, optional
        Per validation run (by name) that continues a recording, that run with
        what came before it in front (:func:`groupfit.continuation.with_histories`):
        the live rule runs through it first, so its state carries into the run.
    stage : callable, optional
        ``stage(name)``: a context each stage without progress of its own runs in
        (:func:`groupfit.running.stage` says when it runs long).
    """
    recordings = recordings or {}
    parts = [modelling] if isinstance(modelling, Run) else list(modelling)
    modelling = join_runs(parts)
    if len(parts) > 1:
        settings = replace(settings, pmax=0, fit_pmax=0)
    validation = [in_modelling_order(modelling, run) for run in validation]
    for run in validation:
        if abs(run.period - modelling.period) > 0.01 * modelling.period:
            raise InputError(
                f"{run.source}: sampled every {run.period:g} s but the modelling run every {modelling.period:g} s"
            )
    runs = [modelling, *validation]
    names = [r.name for r in runs]
    if len(set(names)) != len(names):
        raise InputError(f"two runs share the name '{[n for n in names if names.count(n) > 1][0]}'; rename a file")

    measured = measured_rows(modelling)
    notes = sparse_error_notes(modelling, measured) + joined_run_notes(parts) + rise_notes(modelling, settings)
    X, y = measured.temps, measured.error
    named = pd.DataFrame(X, columns=list(modelling.temp_names))
    mlr = MLR(objective=settings.objective, fit_intercept=settings.fit_intercept).fit(named, y)
    ar1_left_out = ar1_left_out_reason(modelling, measured, parts, settings.heat)
    ar1 = fit_ar1(modelling, settings) if settings.heat is not None and ar1_left_out is None else None

    path, grouped = grouped_path(
        X,
        y,
        path_pmax(modelling, settings.pmax),
        n=settings.n,
        c=settings.c,
        objective=settings.objective,
        fit_intercept=settings.fit_intercept,
        search=settings.search,
        certified=settings.certify_path,
        progress=progress,
    )
    pmax = len(path["breaks"]) - 1
    model_files = {p: model.to_model_file(modelling) for p, model in grouped.items()}
    with stage("break intervals"):
        intervals = {
            p: break_intervals(model, X, y, seed=settings.search.seed, budget_s=AUTO_BUDGET_S, **settings.intervals)
            for p, model in grouped.items()
        }
    with stage("next-run estimate"):
        estimate = next_run_estimate(parts, modelling, measured, settings, pmax, with_ar1=ar1 is not None)
    fit_model = None
    if estimate.fit_penalty is not None:
        with stage("fit's model"):
            fit_model = fit_model_file(
                parts,
                modelling,
                measured,
                ridge_alpha=float(estimate.fit_penalty["alpha"]),
                n=settings.n,
                c=settings.c,
                fit_intercept=settings.fit_intercept,
                objective=settings.objective,
                search=settings.search,
            )
        fit_model = fit_model if differs_from_mlr(fit_model) else None
    files = {"mlr": mlr.to_model_file(modelling), **{f"grouped{p}": f for p, f in model_files.items()}}
    files |= {FIT_KEY: fit_model} if fit_model is not None else {}
    models = FittedModels(mlr, ar1, grouped, files)

    changes = condition_changes(modelling, settings.conditions)
    clamps = {"mlr": float(compensation_clamp(mlr.predict(modelling.temps)))}  # what its model file would hold
    clamps |= {key: float(f.switching.comp_max_um) for key, f in files.items() if key != "mlr"}
    run_notes: list[str] = []
    rows: list[dict[str, Any]] = []
    predictions: dict[str, dict[str, np.ndarray]] = {}
    bands: dict[str, dict[str, tuple]] = {}
    for run in runs:
        is_modelling = run is modelling
        whole = recordings.get(run.name, run)
        if is_modelling:
            preds, bands[run.name] = modelling_predictions(models, parts, modelling, settings)
        else:
            preds, band = validation_predictions(models, whole, run, modelling, settings, live_rule)
            preds, faults, bands[run.name] = replayed_on_faults(
                preds, files, whole, whole.n_samples - run.n_samples, band
            )
            preds, held = clamped(preds, clamps, run.name)
            run_notes += faults + held + (held_heat_notes(run, settings, preds["ar1"]) if ar1 is not None else [])
        predictions[run.name] = preds
        rows += scored_rows(run, preds, grouped, changes if is_modelling else None, fit_model)

    selection = {
        rule: choose_p(
            path["rss"],
            path["R"],
            measured.n_samples,
            X.shape[1] + int(settings.fit_intercept),
            rule,
            settings.p_target if rule == "target" else None,
        )
        for rule in ("bic", "target")
    }
    ar1_summary = None
    if ar1 is not None:
        ar1_summary = {
            "C1": ar1.c1_,
            "C2": {f"{level:g}": value for level, value in ar1.c2_.items()},
            "scaling": settings.ar1_scaling,
            "ljung_box": ar1.ljung_box(),
            "free_run": True,
            "start": settings.ar1_start,
            "fit": settings.ar1_fit,
            "structural_gain_um_per_K": ar1.structural_gain_,
            "heat": settings.heat,
        }
    return ComparisonResult(
        runs=names,
        rows=rows,
        predictions=predictions,
        path=path,
        selection=selection,
        mlr_statistics=mlr.statistics_,
        ar1=ar1_summary,
        break_stability=break_stability(path["breaks"]),
        condition_changes=changes,
        grouped_models=model_files,
        validation_rule="run-time switching" if live_rule is not None else "sample index",
        break_intervals=intervals,
        bands=bands,
        run_conditions={
            run.name: "modelling"
            if run is modelling
            else run_condition(run, modelling, settings.conditions, settings.same_condition_samples)
            for run in runs
        },
        reference=modelling.reference,
        expectation=estimate.expectation,
        ar1_expectation=estimate.ar1_expectation,
        fit_choice=estimate.fit_choice,
        fit_penalty=estimate.fit_penalty,
        fit_model=fit_model,
        notes=notes + run_notes,
        ar1_left_out=ar1_left_out if settings.heat is not None else None,
    )


@dataclass(frozen=True)
class NextRunEstimate:
    """The expected next-run error of p = 0…pmax, the p ``fit`` would choose and the penalty it gives p = 0."""

    expectation: NextRunExpectation
    fit_choice: int | None
    fit_penalty: dict[str, Any] | None
    ar1_expectation: NextRunExpectation | None


def next_run_estimate(
    parts: Sequence[Run], modelling: Run, measured: Run, settings: ComparisonSettings, pmax: int, *, with_ar1: bool
) -> NextRunEstimate:
    """The next-run expectation of every p compared (:mod:`groupfit.heldout.expect`), as ``fit`` decides it."""
    fit_pmax = path_pmax(modelling, settings.fit_pmax)
    candidates = range(max(pmax, fit_pmax) + 1)  # the next-run expectation of p = 0…pmax
    scored_runs = [measured_rows(part) for part in parts] if len(parts) > 1 else [measured]
    expectation = expect_next_run(
        scored_runs, candidates, n=settings.n, c=settings.c, fit_intercept=settings.fit_intercept
    )
    if fit_pmax < settings.fit_pmax:  # the error not on every row: the global model alone
        expectation = expectation.on_measured_rows(measured.n_samples, modelling.n_samples, settings.fit_pmax)
    fit_choice = expectation.choice_among(fit_pmax + 1)
    fit_penalty = (
        penalised_expectation(measured, fit_intercept=settings.fit_intercept, parts=scored_runs)
        if fit_choice == 0
        else None
    )
    ar1_expectation = expect_compared_ar1(modelling, settings) if with_ar1 else None
    return NextRunEstimate(expectation, fit_choice, fit_penalty, ar1_expectation)


def path_pmax(modelling: Run, pmax: int) -> int:
    """The largest p compared or chosen: ``pmax``, or 0 for an error measured on some rows only
    (:func:`sparse_error_notes`)."""
    return pmax if np.isfinite(modelling.error).all() else 0


def sparse_error_notes(modelling: Run, measured: Run) -> list[str]:
    """What a modelling run whose error is measured on some rows only leaves out of the comparison."""
    if measured is modelling:
        return []
    return [
        f"the error of {modelling.name} is measured on {measured.n_samples} of {modelling.n_samples} rows: "
        "compared are the global models fitted on those rows; grouped models (p >= 1) need the error on every "
        "row (their breaks are row indices), the AR(1) model on consecutive rows; every run is scored on its "
        "measured rows"
    ]


def joined_run_notes(parts: Sequence[Run]) -> list[str]:
    """What several modelling runs, joined, leave out of the comparison."""
    if len(parts) < 2:
        return []
    return [
        f"{len(parts)} modelling runs joined ({', '.join(part.name for part in parts)}): compared are the global "
        "models fitted on all of them; grouped models (p >= 1) are fitted on one run (their breaks are row indices "
        "of one run: give one --data and the others as --validate), the AR(1) model on one run; the next-run "
        "figure leaves each run out in turn"
    ]
