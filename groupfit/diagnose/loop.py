"""The diagnosis loop: rank candidates on held-out conditions, add the best while it holds, report before/after.

Acceptance imitates the next run. A candidate is added only when, on folds
that are whole operating conditions or whole runs
(:mod:`groupfit.heldout.folds`), it removes at least ``min_score`` of the
model's held-out squared error and at least ``min_effect_rms_um`` of RMS
(``min_further_effect_rms_um`` for an effect after the first),
lowers the error on more than half of the folds, and at most doubles the RMS
error of any one fold (:data:`MAX_FOLD_WORSENING`): an effect that fits most
conditions at the expense of one (a cold start, the lowest speed) is a fit of
those conditions, not a cause that holds on the next run, however small that
one condition's share of the samples. Stricter tests apply where a chance fit
is most tempting:

* transforms of the model's own inputs (a low-pass of a sensor the model
  already reads) are refused unless asked for (``own_transforms=True``, then
  the every-fold test below): they re-weight information the model has, which
  fits the modelling conditions and rarely the next run; unused temperature
  sensors enter as measured only, for the same reason;
* candidates nearly a copy of one of the model's inputs (|r| ≥ 0.95) must remove
  twice ``min_score``: most of what they add, the model could already say;
* every effect after the first must lower the error on *every* held-out fold:
  a second effect explains what is left of a smaller residual, where a fit to
  one condition is easiest to mistake for an effect.
* when a straight line in time explains the held-out error (a probe creeping,
  a drift nobody logged), a candidate must beat it by more than one standard
  error, or still explain what the line leaves (``drift_guard``): a long
  low-pass of anything that rises over the run follows a drift on held-out
  conditions too.

Among low-passes of the same column that pass, the shortest time constant
whose held-out error is within one standard error of the best one's is taken
(the one-standard-error rule of cross-validation, the standard error from
the spread of the fold-by-fold differences): a longer lag than the data need
turns an effect into a trend of the modelling run, which the next run does
not share, and depends more on how the run started.

On a model of rises over a reference column (the air), each low-pass and
delay of that column is scored twice, as read and over the reference
(``feature − reference``, the reference through a 2-minute low-pass: the lag
of an unsensed part behind the air, which such a model cannot otherwise say);
one added over the reference is written
on absolute readings (:func:`groupfit.diagnose.augment.augment_model_over_reference`).

A cause is preferred to a symptom: an unused temperature sensor is added
only when no cause column (an ambient, a speed, a heat source's on/off)
passes. Other columns that explain the held-out error as well as the one
added (within one standard error) are reported as alternatives.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numpy as np
import pandas as pd

from groupfit.columns import is_ambient_name, is_sensor_column, usable_columns
from groupfit.data import Run
from groupfit.diagnose.augment import (
    augment_model,
    augment_model_over_reference,
    feature_on_runs,
    refit_model,
    steady_reference,
)
from groupfit.diagnose.candidates import (
    COLLINEAR_R,
    EXOGENOUS_R,
    HEAT_EXPONENT,
    Candidate,
    candidate_features,
    largest_correlation,
    rank_candidates,
    within_one_se,
)
from groupfit.diagnose.checks import drift, ljung_box
from groupfit.diagnose.drift_guard import DriftGuard
from groupfit.diagnose.history import started_running_notes, with_histories
from groupfit.diagnose.joint import JointProblem, JointSelection
from groupfit.diagnose.reference import absolute_candidate, absolute_model, droppable_reference, global_view
from groupfit.diagnose.residual import LiveRule, model_inputs, residual
from groupfit.errors import InputError
from groupfit.features import Feature, derived_matrix
from groupfit.heldout.check import overfit_check
from groupfit.heldout.design import group_index, group_sample_floor, stacked_design
from groupfit.heldout.folds import Folds, make_folds, operating_columns
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.metrics import error_metrics

MIN_SCORE = 0.3
"""Least share of the held-out squared error that makes an effect significant."""
MIN_EFFECT_RMS_UM = 0.17
"""Least residual RMS (µm) the first effect must remove out of sample: below it, nothing a compensation would
notice. A low-pass of a heat input that only averages sensor noise removes up to 0.12 µm on the FE run with
nothing missing and realistic noise (``datasets/diag_none_*``); the floor keeps 1.4 times that."""
MIN_FURTHER_EFFECT_RMS_UM = 0.2
"""The same for every effect after the first, which explains what is left of a smaller residual (a fifth of
a typical positioning repeatability)."""
MIN_FOLDS_IMPROVED = 0.5
"""Share of held-out folds an effect must improve (more than this); the strict test asks for all of them."""
OVERFIT_NOTE = "the model over-fits:"
"""How the note on an over-fitting base model begins (the report leaves it out where its head says it)."""
MAX_EFFECTS = 3
MAX_FOLD_WORSENING = 2.0
"""No held-out fold's RMS error may grow by more than this factor when the effect is added."""


@dataclass
class Step:
    """One accepted effect and what it did on the held-out folds."""

    candidate: Candidate
    held_out_rms_before: float
    held_out_rms_after: float
    alternatives: list[Candidate] = field(default_factory=list)
    """Candidates of other columns that explain the held-out error as well (within one standard error)."""
    joint: bool = False
    """Chosen together with the inputs (``select_jointly``): scored against the inputs chosen before it."""

    def to_dict(self) -> dict[str, Any]:
        return {
            **self.candidate.to_dict(),
            "held_out_rms_before_um": self.held_out_rms_before,
            "held_out_rms_after_um": self.held_out_rms_after,
            "alternatives": [c.to_dict() for c in self.alternatives],
            "joint": self.joint,
        }


@dataclass
class Refusal:
    """A candidate that scored well enough but failed the test it faced."""

    candidate: Candidate
    reason: str

    def to_dict(self) -> dict[str, Any]:
        return {**self.candidate.to_dict(), "reason": self.reason}


@dataclass
class DiagnosisResult:
    """What the diagnosis found and did."""

    candidates: list[Candidate]
    added: list[Candidate]
    before: dict[str, Any]
    after: dict[str, Any]
    model: dict[str, Any]
    notes: list[str] = field(default_factory=list)
    checks_before: dict[str, Any] = field(default_factory=dict)
    checks_after: dict[str, Any] = field(default_factory=dict)
    residuals_before: dict[str, np.ndarray] = field(default_factory=dict)
    residuals_after: dict[str, np.ndarray] = field(default_factory=dict)
    steps: list[Step] = field(default_factory=list)
    refused: list[Refusal] = field(default_factory=list)
    folds: str = ""
    base_check: dict[str, Any] = field(default_factory=dict)
    run_names: dict[str, str] = field(default_factory=dict)
    """Names of the modelling run(s) (``"data"``) and the validation run(s) (``"validate"``)."""
    selection: dict[str, Any] | None = None
    """How the inputs were re-selected before the diagnosis (``diagnose --select``), when they were."""
    ridge: dict[str, Any] | None = None
    """The ridge penalty the model was refitted with before the diagnosis (``diagnose --ridge``), when it was."""
    reference: dict[str, Any] | None = None
    """The check of the model's reference sensor against absolute readings (:mod:`groupfit.diagnose.reference`),
    when the model has one; ``dropped`` says whether the model was refitted without it."""
    ambient: tuple[str, ...] = ()
    """Columns declared ambient temperatures (``diagnose --ambient``), whatever their names."""
    validation_runs: list[dict[str, Any]] = field(default_factory=list)
    """Each validation run on its own: ``name``, and the error metrics ``before`` and ``after``."""

    def summary(self) -> str:
        """The report, as ``groupfit diagnose`` prints it."""
        from groupfit.diagnose.report import diagnosis_summary

        return diagnosis_summary(self)

    def to_json(self, model_path: str | None = None) -> dict[str, Any]:
        """The machine-readable result (``diagnose --json``); ``model`` is the model file to use."""
        return {
            "candidates": [c.to_dict() for c in self.candidates],
            "added": [c.to_dict() for c in self.added],
            "steps": [s.to_dict() for s in self.steps],
            "refused": [r.to_dict() for r in self.refused],
            "folds": self.folds,
            "base_model": self.base_check,
            "selection": self.selection,
            "ridge": self.ridge,
            "reference": self.reference,
            "before": self.before,
            "after": self.after,
            "validation_runs": self.validation_runs,
            "improved": self.improved,
            "checks": {"before": self.checks_before, "after": self.checks_after},
            "notes": self.notes,
            "model": None if model_path is None else str(model_path),
        }

    @property
    def changed(self) -> bool:
        """Whether the model differs from the one given: an effect added, inputs re-selected, a ridge refit or its
        reference dropped."""
        dropped = self.reference is not None and self.reference["dropped"]
        return bool(self.added) or self.selection is not None or bool(self.ridge and self.ridge["alpha"]) or dropped

    @property
    def improved(self) -> bool | None:
        """Whether the validation runs got better, together and each one; None without one (or when the model
        was not changed)."""
        if "validate" not in self.before or not self.changed:
            return None
        together = self.after["validate"]["rms_um"] < self.before["validate"]["rms_um"]
        return together and not self.worse_runs

    @property
    def worse_runs(self) -> list[dict[str, Any]]:
        """The validation runs on which the changed model's RMS error is not lower (none when it is unchanged)."""
        if not self.changed:
            return []
        return [r for r in self.validation_runs if r["after"]["rms_um"] >= r["before"]["rms_um"]]


def check_inputs(model: dict[str, Any], run: Run, inputs: np.ndarray) -> list[str]:
    """Refuse runs whose model inputs cannot be evaluated; note dead-looking inputs."""
    notes = []
    for j, name in enumerate(model["temps"]):
        column = inputs[:, j]
        bad = ~np.isfinite(column)
        if bad.all():
            raise InputError(
                f"{run.source}: model input '{name}' has no finite value (a dead sensor): the model cannot be "
                "evaluated; replace the sensor or fit a model without it"
            )
        if bad.any():
            row = int(np.flatnonzero(bad)[0]) + 1
            raise InputError(
                f"{run.source}: model input '{name}' is not finite at row {row} ({int(bad.sum())} rows): "
                "repair or drop those rows before diagnosing"
            )
        if np.ptp(column) == 0.0:
            notes.append(f"model input '{name}' is constant on {run.name} (a dead sensor?)")
    return notes


def metrics_of(res: np.ndarray) -> dict[str, float]:
    return error_metrics(res[np.isfinite(res)])


def metrics_per_run(
    runs: Sequence[Run], skipped: Sequence[int], before: np.ndarray, after: np.ndarray
) -> list[dict[str, Any]]:
    """The error metrics of each of ``runs`` before and after, cut from the stacked residuals (a run's history
    rows, ``skipped``, are not in them); runs without a measured error are left out."""
    edges = np.cumsum([0, *(len(run.time) - skip for run, skip in zip(runs, skipped))])
    out = []
    for run, start, end in zip(runs, edges[:-1], edges[1:]):
        if np.isfinite(before[start:end]).any():
            out.append(
                {"name": run.name, "before": metrics_of(before[start:end]), "after": metrics_of(after[start:end])}
            )
    return out


def as_runs(runs: Run | Sequence[Run] | None) -> list[Run]:
    if runs is None:
        return []
    return [runs] if isinstance(runs, Run) else list(runs)


def joint_name(runs: list[Run]) -> str:
    return runs[0].name if len(runs) == 1 else "+".join(r.name for r in runs)


def diagnose(
    model: dict[str, Any],
    data: Run | Sequence[Run],
    validate: Run | Sequence[Run] | None = None,
    live_rule: LiveRule | None = None,
    min_score: float = MIN_SCORE,
    min_effect_rms_um: float = MIN_EFFECT_RMS_UM,
    max_effects: int = MAX_EFFECTS,
    heat_exponent: float | str = HEAT_EXPONENT,
    own_transforms: bool = False,
    select_jointly: bool = False,
    baseline: dict[str, Any] | None = None,
    check_reference: bool = True,
    min_further_effect_rms_um: float = MIN_FURTHER_EFFECT_RMS_UM,
    ambient: Sequence[str] = (),
    validation_continues: bool = False,
) -> DiagnosisResult:
    """Find what the model misses on ``data``, add it, and judge the result on ``validate``.

    Candidates are chosen on ``data`` only, by held-out folds that are whole
    operating conditions (one run) or whole runs (several); ``validate`` is
    never used to choose, only to report. A model of rises over a reference
    sensor is also diagnosed from absolute readings, and that diagnosis
    replaces this one when its end model predicts the held-out conditions
    clearly better (:func:`absolute_branch`). With ``select_jointly`` the model's
    measured inputs are re-chosen together with the first effects
    (:mod:`groupfit.diagnose.joint`; a global model without derived inputs
    only), the further effects then as usual. ``baseline`` is the model
    before/after compare with (default ``model``; the model as the user gave
    it, when ``model`` is a re-selected or ridge-refitted start). A
    validation run that continues a modelling run is judged with it in front
    (:mod:`groupfit.diagnose.history`), and a modelling run that continues
    another is fitted and scored with it in front, its rows unscored: the
    derived inputs of a log split into files are those of the whole log.
    ``ambient`` names columns that are ambient temperatures whatever their
    names (an air sensor logged as ``T0``): causes, tried with every
    transform, not machine sensors. With ``validation_continues`` each
    validation run is taken to continue the run before it whatever its time
    stamps (a file whose clock starts again).
    """
    data_runs, validate_runs = as_runs(data), as_runs(validate)
    ambient = tuple(ambient)
    for column in ambient:
        missing = [run for run in data_runs if column not in run.frame.columns]
        if missing:
            raise InputError(
                f"{missing[0].source}: --ambient column '{column}' not found; columns: "
                f"{', '.join(map(str, missing[0].frame.columns))}"
            )
        if column in model["temps"]:
            raise InputError(
                f"--ambient {column}: the model reads '{column}' as an input; name a column it does not read "
                "(its transforms would re-weight an input: --own-transforms)"
            )
    if select_jointly and (model["p"] > 0 or model.get("derived_inputs")):
        raise InputError(
            "--select joint re-chooses the inputs of a global model (p = 0) without derived inputs; this model "
            + (f"has p = {model['p']}" if model["p"] > 0 else "already has derived inputs")
            + ": fit one with --p 0 on the measured sensors"
        )
    if len(data_runs) > 1 and model["p"] > 0:
        raise InputError(
            f"{len(data_runs)} modelling runs given for a grouped model (p = {model['p']}): its breaks belong to "
            "one run; diagnose a grouped model on one run, or a global model (p = 0) on several"
        )
    data_runs, history_rows, chain_notes = with_histories(data_runs, [])  # a log split into files: one recording
    period = float(model["sampling_period_s"])
    inputs = [model_inputs(model, run) for run in data_runs]
    notes = [n for run, x in zip(data_runs, inputs) for n in check_inputs(model, run, x)] + chain_notes
    for run in validate_runs:
        notes += check_inputs(model, run, model_inputs(model, run))
    base_columns = {data_runs[0].time_name, model["error"]}
    derived_sources = {d["column"] for d in model.get("derived_inputs", [])}
    used = set(model["temps"]) | derived_sources
    columns, column_notes = common_usable_columns(data_runs, base_columns | used)
    notes += column_notes
    measured_inputs = [t for t in model["temps"] if all(t in r.frame.columns for r in data_runs)]
    stacked_frame = pd.concat([r.frame[columns] for r in data_runs], ignore_index=True)
    operating = operating_columns(stacked_frame, columns) if columns else []
    target = np.concatenate([r.error for r in data_runs])
    measured = np.isfinite(target)
    if not measured.any():
        raise InputError(f"{data_runs[0].source}: the error is measured on no row; diagnose needs it")
    own_rows = len(target) - sum(history_rows)  # the rows of the runs as given, without the histories in front
    if int((~measured).sum()) > sum(history_rows):
        if model["p"] > 0:
            raise InputError(
                f"{data_runs[0].source}: the error is missing on {int((~measured).sum())} rows; a grouped model's "
                "breaks are sample indices of a fully measured run: fill or drop those rows"
            )
        notes.append(
            f"the error is measured on {int(measured.sum())} of {own_rows} rows: the others carry the history "
            "of the derived inputs and are neither fitted nor scored"
        )
    folds = make_folds([r.frame for r in data_runs], columns).restricted(measured)
    grouped = model["p"] > 0
    if grouped:
        folds = folds.within_groups(group_index(model, len(target)), group_sample_floor(model))
    if folds.n_folds < 2:
        raise InputError(f"{data_runs[0].source}: too short to hold out a condition; give a longer run or several")

    runs, skipped = {"data": data_runs}, {"data": list(history_rows)}
    if validate_runs:
        runs["validate"], skipped["validate"], history_notes = with_histories(
            validate_runs, data_runs, assume_continued=validation_continues
        )
        notes += history_notes

    def residuals_of(m: dict[str, Any]) -> dict[str, np.ndarray]:
        return {key: stacked_residual(m, rs, live_rule, skipped[key]) for key, rs in runs.items()}

    before = residuals_of(model if baseline is None else baseline)
    current_model, current_inputs = model, inputs
    current = dict(before) if baseline is None else residuals_of(model)
    scorer = model_scorer(model, target, inputs, folds, measured)
    base_check = overfit_check(scorer, folds, grouped)
    if base_check["overfitted"]:
        notes.append(
            f"{OVERFIT_NOTE} held-out RMS {base_check['held_out_rms_um']:.3g} µm against "
            f"{base_check['in_sample_rms_um']:.3g} µm in sample ({folds.describe()}); effects found on it are "
            f"unreliable: {base_check['advice']}"
        )

    def compute(feature):
        return stacked_feature(feature, data_runs, period)[measured]

    @functools.cache
    def steady_air(reference: str) -> np.ndarray:
        return compute(steady_reference(reference))

    def compute_over(feature: Feature, reference: str) -> np.ndarray:
        """A lag of the air taken over the air (through its 2-minute low-pass)."""
        return compute(feature) - steady_air(reference)

    def values_of(candidate: Candidate) -> np.ndarray:
        return compute(candidate.feature) if candidate.over is None else compute_over(candidate.feature, candidate.over)

    if not own_transforms:
        notes.append("transforms of the model's own inputs not tried (they re-weight what the model reads)")
    sensor_columns = frozenset(c for c in columns if is_sensor_column(c) and c not in ambient)
    air_named = any(is_ambient_name(c) or c in ambient for c in columns)
    if sensor_columns and operating and not air_named:
        exogenous = exogenous_sensors(data_runs, sorted(sensor_columns), operating, period)
        for column in exogenous:
            notes.append(
                f"'{column}' is read as an ambient: no column is named as one, and it does not follow the heat "
                f"sources ({', '.join(operating)}; |r| < {EXOGENOUS_R} with every lag)"
            )
        sensor_columns -= set(exogenous)
        air_named = bool(exogenous)
    if sensor_columns and not air_named:
        unused = ", ".join(sorted(sensor_columns))
        notes.append(
            f"no column is named as an ambient (T_amb, ambient_C, T_room, air…): the unused sensors ({unused}) "
            "were read as machine sensors, tried as measured only; if one of them reads the air, say so with "
            "--ambient COLUMN and its lags are tried as well"
        )
    tried = candidate_features(
        columns,
        measured_inputs if own_transforms else [],
        stacked_frame,
        operating,
        heat_exponent,
        sensor_transforms=own_transforms,
        sensor_columns=sensor_columns,
    )
    ramp = np.concatenate([r.time - r.time[0] for r in data_runs])[measured]
    added: list[Candidate] = []
    steps: list[Step] = []
    refused: list[Refusal] = []
    first_ranking: list[Candidate] | None = None

    def effect_test(candidate: Candidate, drift: DriftGuard) -> str | None:
        if not significant(candidate, min_score, min_effect_rms_um):
            return "removes too little of the held-out error"
        return failed_test(candidate, min_score, False, own_transforms, drift)

    def adopted(m: dict[str, Any]):
        """The model's inputs on the modelling runs, its residuals and its held-out scorer."""
        m_inputs = [model_inputs(m, run) for run in data_runs]
        return m_inputs, residuals_of(m), model_scorer(m, target, m_inputs, folds, measured)

    reference = droppable_reference(model, data_runs) if check_reference else None
    reference_check: dict[str, Any] | None = None

    def drop_reference_if_wrong() -> None:
        """Refit on absolute readings when they beat the reference on the held-out folds
        (:func:`reference_change_refusal`)."""
        nonlocal reference_check, current_model, current_inputs, current, scorer
        absolute, absolute_inputs = absolute_model(current_model, data_runs)
        # a grouped model is judged as one group: the groups' own intercepts absorb the level the reference sets
        given_scorer = (
            model_scorer(global_view(current_model), target, current_inputs, folds, measured) if grouped else scorer
        )
        judged_scorer = model_scorer(
            global_view(absolute) if grouped else absolute, target, absolute_inputs, folds, measured
        )
        candidate = absolute_candidate(reference, given_scorer, judged_scorer)
        reason = reference_change_refusal(candidate, min_score)
        reference_check = {
            "reference": reference,
            "dropped": reason is None,
            "after_effects": len(added),
            "held_out_rms_um": {"given": given_scorer.held_out_rms, "absolute": judged_scorer.held_out_rms},
            "folds_improved": candidate.n_folds_improved,
            "n_folds": folds.n_folds,
            "score": candidate.score,
            "as_one_group": grouped,
            "reason": reason,
        }
        if reason is None:
            current_model, current_inputs, current, scorer = (
                absolute,
                absolute_inputs,
                residuals_of(absolute),
                model_scorer(absolute, target, absolute_inputs, folds, measured) if grouped else judged_scorer,
            )

    if reference is not None:
        drop_reference_if_wrong()

    selection = None
    if select_jointly:
        causes = [f for f in tried if f.column not in sensor_columns and f.column not in model["temps"]]
        current_model, joint, selection = joint_start(
            current_model,
            data_runs,
            current_inputs,
            target,
            measured,
            folds,
            [(f, compute(f)) for f in causes],
            effect_test,
            ramp,
        )
        added, first_ranking = list(joint.effects), joint.first_ranking
        steps = [Step(c, *joint.held_out_around(c), joint=True) for c in added]
        current_inputs, current, scorer = adopted(current_model)
        tried = [f for f in tried if f.column not in {c.feature.column for c in added}]
        if selection["nested_held_out_rms_um"] >= base_check["held_out_rms_um"]:
            notes.append(
                f"the joint selection is not expected to carry to a new condition: chosen again without each "
                f"held-out condition, it predicts it with {selection['nested_held_out_rms_um']:.3g} µm RMS, the "
                f"model as given with {base_check['held_out_rms_um']:.3g} µm"
            )
    while len(added) < max_effects and tried:
        model_inputs_now = np.vstack(current_inputs)[measured]
        ranking = rank_candidates(target[measured], tried, compute, scorer, model_inputs_now, set(measured_inputs))
        over = droppable_reference(current_model, data_runs)
        lags_of_reference = [f for f in tried if f.column == over and f.transform in ("lowpass", "delay")]
        if lags_of_reference:  # a part lagging the air, read over the air as the model reads its sensors
            taken_over = rank_candidates(
                target[measured],
                lags_of_reference,
                functools.partial(compute_over, reference=over),
                scorer,
                model_inputs_now,
            )
            ranking = sorted(ranking + [replace(c, over=over) for c in taken_over], key=lambda c: -c.score)
        if first_ranking is None:
            first_ranking = ranking
        held_out_before = scorer.held_out_rms
        drift = DriftGuard(ramp, scorer, values_of, data_runs[0].time_name)
        best, step_refusals, alternatives = choose(
            ranking,
            min_score,
            max(min_effect_rms_um, min_further_effect_rms_um) if added else min_effect_rms_um,
            bool(added),
            own_transforms,
            sensor_columns,
            drift,
        )
        refused += step_refusals
        if best is None:
            break
        if best.over is None:
            current_model = augment_model(current_model, data_runs, current_inputs, best.feature)
        else:
            current_model = augment_model_over_reference(current_model, data_runs, current_inputs, best.feature)
        current_inputs, current, scorer = adopted(current_model)
        held_out_after = scorer.held_out_rms
        added.append(best)
        steps.append(Step(best, held_out_before, held_out_after, alternatives))
        tried = [f for f in tried if f.column != best.feature.column]
        if reference_check is not None and droppable_reference(current_model, data_runs) is not None:
            drop_reference_if_wrong()  # an effect the reference's misfit hid may now be in

    if reference_check is not None and not reference_check["dropped"] and not select_jointly:
        on_absolute = absolute_branch(
            model,
            data_runs,
            scorer,
            added,
            folds,
            target,
            measured,
            reference_check,
            lambda start: diagnose(
                start,
                data_runs,
                validate_runs or None,
                live_rule,
                min_score=min_score,
                min_effect_rms_um=min_effect_rms_um,
                max_effects=max_effects,
                heat_exponent=heat_exponent,
                own_transforms=own_transforms,
                baseline=model if baseline is None else baseline,
                check_reference=False,
                min_further_effect_rms_um=min_further_effect_rms_um,
                ambient=ambient,
                validation_continues=validation_continues,
            ),
            min_score,
        )
        if on_absolute is not None:
            on_absolute.base_check = base_check
            # the over-fit check is the given model's (base_check), said once
            on_absolute.notes = notes + [
                n for n in on_absolute.notes if n not in notes and not n.startswith(OVERFIT_NOTE)
            ]
            return on_absolute

    if validate_runs:
        notes += started_running_notes(validate_runs, skipped["validate"], [c.feature for c in added])
    time = np.arange(len(before["data"])) * period
    return DiagnosisResult(
        candidates=first_ranking or [],
        added=added,
        before={key: metrics_of(r) for key, r in before.items()},
        after={key: metrics_of(r) for key, r in current.items()},
        model=current_model,
        notes=notes,
        checks_before=residual_checks(before["data"], time),
        checks_after=residual_checks(current["data"], time),
        residuals_before=before,
        residuals_after=current,
        steps=steps,
        refused=refused,
        folds=folds.describe(),
        base_check=base_check,
        run_names={key: joint_name(rs) for key, rs in runs.items()},
        ambient=ambient,
        selection=selection,
        reference=reference_check,
        validation_runs=(
            metrics_per_run(runs["validate"], skipped["validate"], before["validate"], current["validate"])
            if validate_runs
            else []
        ),
    )


def joint_start(
    model: dict[str, Any],
    runs: list[Run],
    inputs: list[np.ndarray],
    target: np.ndarray,
    measured: np.ndarray,
    folds: Folds,
    effects: list[tuple[Feature, np.ndarray]],
    effect_test,
    drift: np.ndarray,
) -> tuple[dict[str, Any], JointSelection, dict[str, Any]]:
    """The model refitted on inputs and effects chosen together, the choice, and what to report of it."""
    stacked = np.vstack(inputs)[measured]
    values = {name: stacked[:, j] for j, name in enumerate(model["temps"])}
    problem = JointProblem(target[measured], values, effects, folds, effect_test, drift, bool(model["intercept"]))
    chosen = problem.select()
    keep = [model["temps"].index(name) for name in chosen.inputs]
    features = [effect.feature for effect in chosen.effects]
    period = float(model["sampling_period_s"])
    columns = [np.column_stack([x[:, keep], derived_matrix(features, r.frame, period)]) for x, r in zip(inputs, runs)]
    current = refit_model(model, runs, columns, [*chosen.inputs, *(f.name for f in features)], features)
    info = {
        "method": "joint",
        "inputs": chosen.inputs,
        "of": len(model["temps"]),
        "order": chosen.order,
        "folds": folds.describe(),
        "nested_held_out_rms_um": problem.nested_held_out_rms(),
    }
    return current, chosen, info


def choose(
    ranking: list[Candidate],
    min_score: float,
    min_effect_rms_um: float,
    further: bool,
    own_transforms: bool = False,
    sensor_columns: frozenset[str] = frozenset(),
    drift: DriftGuard | None = None,
) -> tuple[Candidate | None, list[Refusal], list[Candidate]]:
    """The candidate to add, the refusals on the way, and other columns that explain the error as well.

    The best *cause* that passes its test — an ambient, a speed, a heat
    source's on/off, any column but the machine's temperature sensors — then
    the shortest adequate low-pass of its family. An unused temperature
    sensor is a symptom of some cause, not an effect: it is added only when
    no cause passes (a better sensor set is the job of ``fit --select``).
    """
    refusals = []
    passing = []
    for candidate in ranking:
        if not significant(candidate, min_score, min_effect_rms_um):
            break
        reason = failed_test(candidate, min_score, further, own_transforms, drift)
        if reason:
            if not passing:
                refusals.append(Refusal(candidate, reason))
            continue
        passing.append(candidate)
    if not passing:
        return None, refusals, []
    causes = [c for c in passing if c.feature.column not in sensor_columns]
    best = causes[0] if causes else passing[0]
    chosen = shortest_adequate_lag(best, [c for c in passing if c.family() == best.family()])
    alternatives, seen = [], {chosen.feature.column}
    for c in passing:
        if c.feature.column not in seen and within_one_se(c, passing[0]):
            alternatives.append(c)
            seen.add(c.feature.column)
    return chosen, refusals, alternatives


def reference_change_refusal(candidate: Candidate, min_score: float) -> str | None:
    """Why absolute readings, scored like a first effect, fail the test of a change of reference; or None.

    The test of a first effect without its least RMS and its drift guard: the two models differ in the
    reference sensor's weight, not by a new regressor.
    """
    if candidate.score < min_score:
        return (
            f"removes {100 * candidate.score:.0f} % of the held-out error; a change of reference needs "
            f"{100 * min_score:.0f} %"
        )
    return failed_test(candidate, min_score, False)


def absolute_branch(
    model: dict[str, Any],
    data_runs: list[Run],
    scorer: HeldOutScorer,
    added: list[Candidate],
    folds: Folds,
    target: np.ndarray,
    measured: np.ndarray,
    reference_check: dict[str, Any],
    diagnose_from,
    min_score: float,
) -> DiagnosisResult | None:
    """The diagnosis on absolute readings when it beats the one on rises with the effects of each in; else None.

    The reference check before the effects compares two models that both
    miss the effect; when the missing effect dominates the held-out error,
    neither reading wins clearly and the wrong one is kept, and with it the
    effect is not found at all. So the diagnosis is also run from the model
    on absolute readings, and the two end models face the test of a
    reference change on the same held-out folds. When the diagnosis on rises
    added the reference sensor as measured, its end model is the one on
    absolute readings with the air's weight freed: the one on absolute
    readings then wins when it predicts within one standard error as well,
    with that coefficient fewer. A branch that needs the
    reference column itself (a lag of the air on absolute readings) is not
    evidence against the reference: it gives the air a free weight, which
    the diagnosis on rises already tried as a lag over the reference. The
    outcome is recorded in ``reference_check["branch"]``.
    """
    reference = reference_check["reference"]
    start, _ = absolute_model(model, data_runs)
    branch = diagnose_from(start)
    branch_inputs = [model_inputs(branch.model, run) for run in data_runs]
    branch_scorer = model_scorer(branch.model, target, branch_inputs, folds, measured)
    candidate = absolute_candidate(reference, scorer, branch_scorer)
    needs_reference = any(c.feature.column == reference for c in branch.added)
    if needs_reference:
        reason = f"the effects found on absolute readings include `{reference}` itself: not evidence against it"
    else:
        reason = reference_change_refusal(candidate, min_score)
    frees_reference = any(c.feature.column == reference and c.feature.transform == "identity" for c in added)
    as_well = (
        reason is not None
        and not needs_reference
        and frees_reference
        and within_one_se(candidate, absolute_candidate(reference, scorer, scorer))
    )
    if as_well:
        reason = None
    outcome = {
        "effects": {
            "given": [c.feature.name for c in added],
            "absolute": [c.feature.name for c in branch.added],
        },
        "held_out_rms_um": {"given": scorer.held_out_rms, "absolute": branch_scorer.held_out_rms},
        "folds_improved": candidate.n_folds_improved,
        "score": candidate.score,
        "as_well_with_fewer_coefficients": as_well,
        "reason": reason,
    }
    reference_check["branch"] = outcome
    if reason is not None:
        return None
    branch.reference = {
        **reference_check,
        "dropped": True,
        "held_out_rms_um": outcome["held_out_rms_um"],
        "folds_improved": candidate.n_folds_improved,
        "score": candidate.score,
        "reason": None,
    }
    return branch


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


def failed_test(
    candidate: Candidate,
    min_score: float,
    further: bool,
    own_transforms: bool = False,
    drift: DriftGuard | None = None,
) -> str | None:
    """Why the candidate fails the test it faces, or None; ``drift``: the straight drift it must be told from."""
    n_folds = len(candidate.fold_ratios)
    improved = candidate.n_folds_improved
    if candidate.own_input and not own_transforms:
        return "a transform of the model's own input: refused (it re-weights what the model already reads)"
    if candidate.own_input or further:
        if improved < n_folds:
            why = "a transform of the model's own input" if candidate.own_input else "a further effect"
            return f"{why} must lower the error on every held-out fold; it lowers it on {improved} of {n_folds}"
    if candidate.collinearity >= COLLINEAR_R and candidate.score < 2.0 * min_score:
        return (
            f"collinear with a model input (|r| {candidate.collinearity:.2f}): it must remove "
            f"{200 * min_score:.0f} % of the held-out error"
        )
    worst = int(np.argmax(candidate.fold_ratios))
    if candidate.fold_ratios[worst] > MAX_FOLD_WORSENING**2:
        return (
            f"makes one held-out condition (fold {worst + 1}) {np.sqrt(candidate.fold_ratios[worst]):.1f} times "
            "worse (RMS)"
        )
    if candidate.folds_improved <= MIN_FOLDS_IMPROVED:
        return f"lowers the error on only {improved} of {n_folds} held-out folds"
    if drift is not None:
        return drift.refusal(candidate, min_score)
    return None


def significant(candidate: Candidate, min_score: float, min_effect_rms_um: float) -> bool:
    """Whether the candidate removes enough of the held-out error to be an effect at all."""
    return candidate.score >= min_score and candidate.explained_rms_um >= min_effect_rms_um


def shortest_adequate_lag(best: Candidate, family: list[Candidate]) -> Candidate:
    """The shortest low-pass of ``family`` whose held-out error is within one standard error of ``best``'s."""
    if best.feature.transform != "lowpass":
        return best
    adequate = [best, *(c for c in family if c.feature.transform == "lowpass" and within_one_se(c, best))]
    return min(adequate, key=lambda c: c.feature.tau_s)


def common_usable_columns(runs: list[Run], exclude: set[str]) -> tuple[list[str], list[str]]:
    """Columns present in every run and usable over all of them together."""
    common = [c for c in runs[0].frame.columns if all(c in run.frame.columns for run in runs[1:])]
    notes = [f"column '{c}' left out: missing on some of the runs" for c in runs[0].frame.columns if c not in common]
    stacked = pd.concat([run.frame[common] for run in runs], ignore_index=True)
    columns, more_notes = usable_columns(stacked, exclude)
    return columns, notes + more_notes


def stacked_residual(
    model: dict[str, Any], runs: list[Run], live_rule: LiveRule | None, skipped: Sequence[int] | None = None
) -> np.ndarray:
    """The residuals on ``runs``, stacked, each without its first ``skipped`` rows (a history put in front)."""
    skipped = skipped or [0] * len(runs)
    return np.concatenate([residual(model, run, live_rule)[skip:] for run, skip in zip(runs, skipped)])


def model_scorer(
    model: dict[str, Any], target: np.ndarray, inputs: list[np.ndarray], folds: Folds, rows: np.ndarray
) -> HeldOutScorer:
    """The held-out scorer of the model's own design on ``rows``, fitted as the model is (least squares or ridge)."""
    ridge = model.get("ridge_alpha") or 0.0
    design = stacked_design(model, inputs)[rows]
    return HeldOutScorer(target[rows], design, folds, ridge_alpha=ridge, fit_intercept=model["intercept"])


def residual_checks(res: np.ndarray, time_s: np.ndarray) -> dict[str, Any]:
    rows = np.isfinite(res)
    return {"ljung_box": ljung_box(res[rows]), "drift": drift(res[rows], time_s[rows])}
