"""The diagnosis's problem: the runs, the target, the scored rows, the folds and the period, as one object.

:func:`diagnosis_problem` checks the runs against the model (every refusal
an :class:`~groupfit.errors.InputError` naming the file and what to do),
puts a run's history in front of it (a log split into files is one
recording), finds the usable columns and the operating conditions, and
builds the held-out folds. The :class:`Problem` then computes what every
stage needs on the scored rows: a feature's values (each computed once), a
model's residuals on the modelling and validation runs, and its held-out
scorer.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.columns import usable_columns
from groupfit.data import Run
from groupfit.diagnose.augment import feature_on_runs, steady_reference
from groupfit.diagnose.candidates import EXOGENOUS_R, Candidate, candidate_features, largest_correlation
from groupfit.diagnose.history import with_histories
from groupfit.diagnose.notes import COLUMNS, HISTORY, INPUTS, UNSCORED, Note, notes_of
from groupfit.diagnose.residual import LiveRule, clamped_samples, model_inputs, residual
from groupfit.errors import InputError
from groupfit.features import Feature
from groupfit.heldout.design import group_index, group_sample_floor, stacked_design
from groupfit.heldout.folds import Folds, make_folds, operating_columns
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.model import ModelFile
from groupfit.reference import refuse_as_temperature
from groupfit.resample import GAP_PERIODS

Model = ModelFile
"""The model the diagnosis holds (its JSON object only where it is read or written)."""


@dataclass(frozen=True)
class Fit:
    """A model as the diagnosis holds it: its inputs on the modelling runs, its residuals, its held-out scorer."""

    model: Model
    inputs: list[np.ndarray]
    residuals: dict[str, np.ndarray]
    scorer: HeldOutScorer


@dataclass
class Problem:
    """The runs and what is scored on them; features computed once (:meth:`values`)."""

    runs: dict[str, list[Run]]
    """The modelling runs (``"data"``) and the validation runs (``"validate"``), each with its history in front."""
    skipped: dict[str, list[int]]
    """The history rows in front of each run, by the same keys: not scored."""
    period: float
    target: np.ndarray
    measured: np.ndarray
    """The scored rows: where the error is measured."""
    folds: Folds
    columns: list[str]
    """The usable columns the model does not read: the candidates' sources."""
    operating: list[str]
    """The columns that set the operating conditions (speeds, on/off of heat sources)."""
    measured_inputs: list[str]
    live_rule: LiveRule | None = None
    grouped: bool = False
    _values: dict[tuple[Feature, str | None], np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def data(self) -> list[Run]:
        return self.runs["data"]

    @property
    def ramp(self) -> np.ndarray:
        """Time since the start of each modelling run, on the scored rows: the straight drift."""
        return np.concatenate([r.time - r.time[0] for r in self.data])[self.measured]

    def frame(self) -> pd.DataFrame:
        """The modelling runs' candidate columns, stacked."""
        return pd.concat([r.frame[self.columns] for r in self.data], ignore_index=True)

    def values(self, feature: Feature, over: str | None = None) -> np.ndarray:
        """``feature`` on the scored rows, each run from its own start; ``over``: less the reference's 2-minute
        low-pass (a lag of the air taken over the air)."""
        key = (feature, over)
        if key not in self._values:
            values = np.concatenate(feature_on_runs(feature, self.data, self.period))[self.measured]
            self._values[key] = values if over is None else values - self.values(steady_reference(over))
        return self._values[key]

    def candidate_values(self, candidate: Candidate) -> np.ndarray:
        return self.values(candidate.feature, candidate.over)

    def residuals(self, model: Model) -> dict[str, np.ndarray]:
        """The model's residuals on the modelling and validation runs, stacked, histories left out."""
        return {
            key: stacked_residual(model, rs, self.live_rule, self.skipped[key], next_run=key == "validate")
            for key, rs in self.runs.items()
        }

    def clamped(self, model: Model) -> dict[str, int]:
        """Per validation run, on how many of its samples (histories left out) the compensation's clamp holds
        the model's prediction (replay scores them so, and so does the diagnosis)."""
        runs = zip(self.runs.get("validate", []), self.skipped.get("validate") or [])
        return {run.name: clamped_samples(model, run, self.live_rule, skip) for run, skip in runs}

    def scorer(self, model: Model, inputs: list[np.ndarray]) -> HeldOutScorer:
        """The held-out scorer of the model's own design, fitted as the model is (least squares or ridge)."""
        return model_scorer(model, self.target, inputs, self.folds, self.measured)

    def inputs(self, model: Model) -> list[np.ndarray]:
        return [model_inputs(model, run) for run in self.data]

    def fit(self, model: Model) -> Fit:
        """The model adopted: its inputs, residuals and held-out scorer."""
        inputs = self.inputs(model)
        return Fit(model, inputs, self.residuals(model), self.scorer(model, inputs))


def diagnosis_problem(
    model: Model,
    data_runs: list[Run],
    validate_runs: list[Run],
    *,
    live_rule: LiveRule | None,
    validation_continues: bool,
    data_as_logged: Sequence[Run] | None = None,
) -> tuple[Problem, list[Note]]:
    """The problem of diagnosing ``model`` on ``data_runs`` (judged on ``validate_runs``), and the notes on it.

    ``data_as_logged``: ``data_runs`` with their temperature glitches kept as logged (``data_runs`` has them
    interpolated for the fit), put in front of a validation run that continues them, as ``replay`` reads the
    modelling file; by default ``data_runs`` themselves.
    """
    data_runs, history_rows, chain_notes = with_histories(data_runs, [])  # a log split into files: one recording
    notes = [Note(INPUTS, n) for run in data_runs for n in check_inputs(model, run, model_inputs(model, run))]
    notes += notes_of(HISTORY, chain_notes)
    for run in validate_runs:
        notes += notes_of(INPUTS, check_inputs(model, run, model_inputs(model, run), next_run=True))
    used = set(model.temps) | {feature.column for feature in model.derived_inputs or ()}
    columns, column_notes = common_usable_columns(data_runs, {data_runs[0].time_name, model.error} | used)
    notes += notes_of(COLUMNS, column_notes)
    stacked_frame = pd.concat([r.frame[columns] for r in data_runs], ignore_index=True)
    target = np.concatenate([r.error for r in data_runs])
    measured = np.isfinite(target)
    if not measured.any():
        raise InputError(f"{data_runs[0].source}: the error is measured on no row; diagnose needs it")
    own_rows = len(target) - sum(history_rows)  # the rows of the runs as given, without the histories in front
    if int((~measured).sum()) > sum(history_rows):
        if model.p > 0:
            raise InputError(
                f"{data_runs[0].source}: the error is missing on {int((~measured).sum())} rows; a grouped model's "
                "breaks are sample indices of a fully measured run: fill or drop those rows"
            )
        notes.append(
            Note(
                UNSCORED,
                f"the error is measured on {int(measured.sum())} of {own_rows} rows: the others carry the history "
                "of the derived inputs and are neither fitted nor scored",
            )
        )
    folds = make_folds([r.frame for r in data_runs], columns).restricted(measured)
    if model.p > 0:
        folds = folds.within_groups(group_index(model, len(target)), group_sample_floor(model))
    if folds.n_folds < 2:
        raise InputError(f"{data_runs[0].source}: too short to hold out a condition; give a longer run or several")
    runs, skipped = {"data": data_runs}, {"data": list(history_rows)}
    if validate_runs:
        in_front = data_runs if data_as_logged is None else with_histories(data_as_logged, [])[0]
        runs["validate"], skipped["validate"], history_notes = with_histories(
            validate_runs, in_front, assume_continued=validation_continues
        )
        notes += notes_of(HISTORY, history_notes)
    problem = Problem(
        runs=runs,
        skipped=skipped,
        period=float(model.sampling_period_s),
        target=target,
        measured=measured,
        folds=folds,
        columns=columns,
        operating=operating_columns(stacked_frame, columns) if columns else [],
        measured_inputs=[t for t in model.temps if all(t in r.frame.columns for r in data_runs)],
        live_rule=live_rule,
        grouped=model.p > 0,
    )
    return problem, notes


def check_arguments(model: Model, data_runs: list[Run], *, ambient: Sequence[str], select_jointly: bool) -> None:
    """Refuse what the diagnosis cannot do with this model and these runs."""
    for column in ambient:
        missing = [run for run in data_runs if column not in run.frame.columns]
        if missing:
            raise InputError(
                f"{missing[0].source}: --ambient column '{column}' not found; columns: "
                f"{', '.join(map(str, missing[0].frame.columns))}"
            )
        refuse_as_temperature(data_runs[0], column, "--ambient column")
        if column in model.temps:
            raise InputError(
                f"--ambient {column}: the model reads '{column}' as an input; name a column it does not read "
                "(its transforms would re-weight an input: --own-transforms)"
            )
    if select_jointly and (model.p > 0 or model.derived_inputs):
        raise InputError(
            "--select joint re-chooses the inputs of a global model (p = 0) without derived inputs; this model "
            + (f"has p = {model.p}" if model.p > 0 else "already has derived inputs")
            + ": fit one with --p 0 on the measured sensors"
        )
    if len(data_runs) > 1 and model.p > 0:
        raise InputError(
            f"{len(data_runs)} modelling runs given for a grouped model (p = {model.p}): its breaks belong to "
            "one run; diagnose a grouped model on one run, or a global model (p = 0) on several"
        )


def _read_at(run: Run, column: str, row: int) -> bool:
    """Whether ``column`` of the run's table holds a finite reading at the 1-based ``row``."""
    if column not in run.frame.columns:
        return False
    return bool(np.isfinite(pd.to_numeric(run.frame[column].iloc[[row - 1]], errors="coerce")).all())


def check_inputs(model: Model, run: Run, inputs: np.ndarray, *, next_run: bool = False) -> list[str]:
    """Refuse runs whose model inputs cannot be evaluated; note dead-looking inputs.

    ``next_run``: a validation run, read as ``replay`` reads a next run: an
    input that is not a number on some rows is a sensor fault of the run-time
    rule (:mod:`groupfit.rule_faults`), not refused; one that is never a
    number is.
    """
    notes = []
    for j, name in enumerate(model.temps):
        column = inputs[:, j]
        bad = ~np.isfinite(column)
        if bad.all():
            raise InputError(
                f"{run.source}: model input '{name}' has no finite value (a dead sensor): the model cannot be "
                "evaluated; replace the sensor or fit a model without it"
            )
        if bad.any() and not next_run:
            row = int(np.flatnonzero(bad)[0]) + 1
            reference = getattr(model, "reference", None)
            what = f"model input '{name}'"
            if reference in run.frame.columns and _read_at(run, name, row) and not _read_at(run, reference, row):
                what = f"the reference '{reference}' of model input '{name}'"
            raise InputError(
                f"{run.source}: {what} is not finite at row {row} ({int(bad.sum())} rows): "
                "repair or drop those rows before diagnosing, or let --resample SECONDS interpolate up to "
                f"{GAP_PERIODS} missed readings in a row"
            )
        if np.ptp(column[~bad]) == 0.0:
            notes.append(f"model input '{name}' is constant on {run.name} (a dead sensor?)")
    return notes


def common_usable_columns(runs: list[Run], exclude: set[str]) -> tuple[list[str], list[str]]:
    """Columns present in every run and usable over all of them together."""
    common = [c for c in runs[0].frame.columns if all(c in run.frame.columns for run in runs[1:])]
    notes = [f"column '{c}' left out: missing on some of the runs" for c in runs[0].frame.columns if c not in common]
    stacked = pd.concat([run.frame[common] for run in runs], ignore_index=True)
    columns, more_notes = usable_columns(stacked, exclude)
    return columns, notes + more_notes


def stacked_feature(feature: Feature, runs: list[Run], period: float) -> np.ndarray:
    """``feature`` computed on each run from its own start, the runs stacked."""
    return np.concatenate(feature_on_runs(feature, runs, period))


def exogenous_sensors(runs: list[Run], sensors: list[str], operating: list[str], period: float) -> list[str]:
    """Sensors whose correlation with every lag of every heat source stays below :data:`EXOGENOUS_R`."""
    frame = pd.concat([r.frame for r in runs], ignore_index=True)
    lags = [
        stacked_feature(f, runs, period)
        for f in candidate_features(operating, [], frame, operating)
        if f.transform in ("identity", "lowpass")
    ]
    found = []
    for column in sensors:
        values = frame[column].to_numpy(dtype=float)
        if largest_correlation(values, np.column_stack(lags)) < EXOGENOUS_R:
            found.append(column)
    return found


def stacked_residual(
    model: Model,
    runs: list[Run],
    live_rule: LiveRule | None,
    skipped: Sequence[int] | None = None,
    *,
    next_run: bool = False,
) -> np.ndarray:
    """The residuals on ``runs``, stacked, each without its first ``skipped`` rows (a history put in front);
    ``next_run``: validation runs, whose faulty readings the run-time rule takes (:func:`residual`)."""
    skipped = skipped or [0] * len(runs)
    return np.concatenate(
        [residual(model, run, live_rule, next_run=next_run)[skip:] for run, skip in zip(runs, skipped)]
    )


def model_scorer(model: Model, target: np.ndarray, inputs: list[np.ndarray], folds: Folds, rows: np.ndarray):
    """The held-out scorer of the model's own design on ``rows``, fitted as the model is (least squares or ridge)."""
    ridge = model.ridge_alpha or 0.0
    design = stacked_design(model, inputs)[rows]
    return HeldOutScorer(target[rows], design, folds, ridge_alpha=ridge, fit_intercept=model.intercept)
