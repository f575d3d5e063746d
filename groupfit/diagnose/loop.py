"""The diagnosis as a pipeline of stages: rank candidates on held-out conditions, add the best while it holds.

The stages, in order: the problem is built (:mod:`groupfit.diagnose.problem`);
the model's reference sensor is checked against absolute readings
(:mod:`groupfit.diagnose.branch`); with ``select_jointly`` the inputs and
the first effects are chosen together (:mod:`groupfit.diagnose.joint`);
the effect loop adds the best candidate while one passes
(:mod:`groupfit.diagnose.effects`); when the reference survived, the
diagnosis from absolute readings competes with this one. Every threshold
of acceptance is in :class:`~groupfit.diagnose.policy.AcceptancePolicy`.

Acceptance imitates the next run. A candidate is added only when, on folds
that are whole operating conditions or whole runs
(:mod:`groupfit.heldout.folds`), it removes at least ``min_score`` of the
model's held-out squared error and at least ``min_effect_rms_um`` of RMS
(``min_further_effect_rms_um`` for an effect after the first),
lowers the error on more than half of the folds, and at most doubles the RMS
error of any one fold (``max_fold_worsening``): an effect that fits most
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

from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np

from groupfit.data import Run
from groupfit.diagnose.augment import augment_model, augment_model_over_reference
from groupfit.diagnose.branch import absolute_branch, reference_stage
from groupfit.diagnose.candidates import HEAT_EXPONENT, Candidate
from groupfit.diagnose.drift_guard import DriftGuard
from groupfit.diagnose.effects import Tried, choose, ranking, tried_features
from groupfit.diagnose.history import started_running_notes
from groupfit.diagnose.joint import joint_start
from groupfit.diagnose.measures import joint_name, metrics_of, metrics_per_run, residual_checks
from groupfit.diagnose.notes import CLAMP, COLD_START, FAULTS, OVERFIT, Note, notes_of
from groupfit.diagnose.policy import DEFAULT_POLICY, AcceptancePolicy
from groupfit.diagnose.problem import Fit, Model, Problem, check_arguments, diagnosis_problem
from groupfit.diagnose.reference import droppable_reference
from groupfit.diagnose.residual import LiveRule, ModelLike
from groupfit.diagnose.result import DiagnosisResult, InputSelection, ReferenceCheck, Refused, Step
from groupfit.errors import InputError
from groupfit.heldout.check import overfit_check
from groupfit.model import ModelFile
from groupfit.rule_faults import has_faulty_readings, rule_faults, unscored_note, unscored_samples

MIN_SCORE = DEFAULT_POLICY.min_score
MIN_EFFECT_RMS_UM = DEFAULT_POLICY.min_effect_rms_um
MIN_FURTHER_EFFECT_RMS_UM = DEFAULT_POLICY.min_further_effect_rms_um
MAX_EFFECTS = DEFAULT_POLICY.max_effects


@dataclass(frozen=True)
class DiagnoseOptions:
    """How to diagnose, besides the model and the runs (:func:`diagnose` documents each)."""

    policy: AcceptancePolicy = DEFAULT_POLICY
    live_rule: LiveRule | None = None
    heat_exponent: float | str = HEAT_EXPONENT
    select_jointly: bool = False
    baseline: Model | None = None
    check_reference: bool = True
    ambient: tuple[str, ...] = ()
    validation_continues: bool = False
    data_as_logged: tuple[Run, ...] | None = None


@dataclass
class State:
    """What the stages have done so far: the model they hold, the effects added, what was refused, the notes."""

    current: Fit
    tried: Tried
    notes: list[Note]
    added: list[Candidate] = field(default_factory=list)
    steps: list[Step] = field(default_factory=list)
    refused: list[Refused] = field(default_factory=list)
    first_ranking: list[Candidate] | None = None
    reference: ReferenceCheck | None = None
    selection: InputSelection | None = None


def diagnose(
    model: ModelLike,
    data: Run | Sequence[Run],
    validate: Run | Sequence[Run] | None = None,
    live_rule: LiveRule | None = None,
    *,
    min_score: float = MIN_SCORE,
    min_effect_rms_um: float = MIN_EFFECT_RMS_UM,
    max_effects: int = MAX_EFFECTS,
    heat_exponent: float | str = HEAT_EXPONENT,
    own_transforms: bool = False,
    select_jointly: bool = False,
    baseline: ModelLike | None = None,
    check_reference: bool = True,
    min_further_effect_rms_um: float = MIN_FURTHER_EFFECT_RMS_UM,
    ambient: Sequence[str] = (),
    validation_continues: bool = False,
    data_as_logged: Sequence[Run] | None = None,
) -> DiagnosisResult:
    """Find what the model misses on ``data``, add it, and judge the result on ``validate``.

    Candidates are chosen on ``data`` only, by held-out folds that are whole
    operating conditions (one run) or whole runs (several); ``validate`` is
    never used to choose, only to report. A model of rises over a reference
    sensor is also diagnosed from absolute readings, and that diagnosis
    replaces this one when its end model predicts the held-out conditions
    clearly better (:func:`~groupfit.diagnose.branch.absolute_branch`). With ``select_jointly`` the model's
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
    stamps (a file whose clock starts again). ``data_as_logged``: the
    modelling runs with their temperature glitches kept as logged (``data``
    has them interpolated for the fit), the history in front of a validation
    run that continues them, as ``replay`` reads the modelling file (default
    ``data``). The thresholds (``min_score``,
    ``min_effect_rms_um``, ``min_further_effect_rms_um``, ``max_effects``,
    ``own_transforms``) are those of the :class:`~groupfit.diagnose.policy.AcceptancePolicy`.
    """
    policy = AcceptancePolicy(
        min_score=min_score,
        min_effect_rms_um=min_effect_rms_um,
        min_further_effect_rms_um=min_further_effect_rms_um,
        max_effects=max_effects,
        own_transforms=own_transforms,
    )
    options = DiagnoseOptions(
        policy=policy,
        live_rule=live_rule,
        heat_exponent=heat_exponent,
        select_jointly=select_jointly,
        baseline=None if baseline is None else ModelFile.coerce(baseline),
        check_reference=check_reference,
        ambient=tuple(ambient),
        validation_continues=validation_continues,
        data_as_logged=None if data_as_logged is None else tuple(as_runs(data_as_logged)),
    )
    return diagnose_with(ModelFile.coerce(model), as_runs(data), as_runs(validate), options)


def diagnose_with(model: Model, data_runs: list[Run], validate_runs: list[Run], options: DiagnoseOptions):
    """:func:`diagnose` with its settings in one object: the stages in order."""
    check_arguments(model, data_runs, ambient=options.ambient, select_jointly=options.select_jointly)
    problem, notes = diagnosis_problem(
        model,
        data_runs,
        validate_runs,
        live_rule=options.live_rule,
        validation_continues=options.validation_continues,
        data_as_logged=options.data_as_logged,
    )
    before = problem.residuals(model if options.baseline is None else options.baseline)
    if "validate" in before and not np.isfinite(before["validate"]).any():
        raise InputError(
            f"{validate_runs[0].source}: no sample of the validation run(s) is left to judge the model on: the "
            "run-time rule is in sensor fault wherever the error is measured (a reading that is not a number, or "
            "outside its valid range, for longer than its hold); repair those readings or leave the run out"
        )
    inputs = problem.inputs(model)
    residuals = dict(before) if options.baseline is None else problem.residuals(model)
    current = Fit(model, inputs, residuals, problem.scorer(model, inputs))
    base_check = overfit_check(current.scorer, problem.folds, grouped=problem.grouped)
    if base_check.overfitted:
        notes.append(
            Note(
                OVERFIT,
                f"the model over-fits: held-out RMS {base_check.held_out_rms_um:.3g} µm against "
                f"{base_check.in_sample_rms_um:.3g} µm in sample ({problem.folds.describe()}); effects found on "
                f"it are unreliable: {base_check.advice}",
            )
        )
    policy = options.policy
    tried, tried_notes = tried_features(
        problem,
        model.temps,
        ambient=options.ambient,
        heat_exponent=options.heat_exponent,
        own_transforms=policy.own_transforms,
    )
    state = State(current, tried, notes + tried_notes)
    reference = droppable_reference(model, problem.data) if options.check_reference else None
    if reference is not None:
        state.current, state.reference = reference_stage(problem, current, reference, after_effects=0, policy=policy)
    if options.select_jointly:
        start = joint_start(problem, state.current, state.tried, policy, base_check)
        state.current, state.selection, state.first_ranking = start.current, start.selection, start.first_ranking
        state.added, state.steps = list(start.effects), list(start.steps)
        taken = {c.feature.column for c in state.added}
        state.tried = replace(state.tried, features=[f for f in state.tried.features if f.column not in taken])
        state.notes += start.notes
    effect_loop(problem, state, policy)
    if state.reference is not None and not state.reference.dropped and not options.select_jointly:
        baseline = model if options.baseline is None else options.baseline
        on_absolute, state.reference = absolute_branch(
            model,
            problem,
            state.current,
            state.added,
            state.reference,
            diagnose_from=lambda start: diagnose_with(
                start,
                problem.data,
                validate_runs,
                replace(options, baseline=baseline, check_reference=False),
            ),
            policy=policy,
        )
        if on_absolute is not None:
            # the over-fit check is the given model's (base_check), said once
            kept = [n for n in on_absolute.notes if n not in state.notes and n.kind != OVERFIT]
            return replace(on_absolute, base_check=base_check, notes=(*state.notes, *kept))
    if validate_runs:
        features = [c.feature for c in state.added]
        state.notes += notes_of(COLD_START, started_running_notes(validate_runs, problem.skipped["validate"], features))
        baseline = model if options.baseline is None else options.baseline
        state.notes += notes_of(CLAMP, clamp_notes(problem, baseline, state.current.model))
        state.notes += notes_of(FAULTS, fault_notes(problem, baseline, state.current.model))
    return result_of(problem, state, before=before, base_check=base_check, ambient=options.ambient)


def clamp_notes(problem: Problem, before: Model, after: Model) -> list[str]:
    """A note per validation run on which the compensation's clamp held the prediction, before or after."""
    counts = {"before": problem.clamped(before), "after": problem.clamped(after)}
    return [
        f"{name}: the compensation's clamp (twice the largest prediction on the modelling run) held the "
        f"prediction on {counts['before'][name]} sample(s) before and {counts['after'][name]} after; the figures "
        "count what the controller corrects, up to the clamp, as replay does"
        for name in counts["before"]
        if counts["before"][name] or counts["after"][name]
    ]


def fault_notes(problem: Problem, before: Model, after: Model) -> list[str]:
    """A note per validation run with a reading the run-time rule takes as a fault (not a number, or outside its
    valid range): the samples its faults leave unscored (as replay leaves them), after, and before when that
    differs."""
    if problem.live_rule is None:
        return []
    before, after = ModelFile.coerce(before), ModelFile.coerce(after)
    notes = []
    for run, skip in zip(problem.runs.get("validate", []), problem.skipped.get("validate") or []):
        if not (has_faulty_readings(before, run) or has_faulty_readings(after, run)):
            continue  # every reading within its valid range: nothing to replay
        faults = [rule_faults(model, run, skip) for model in (before, after)]
        counts = [unscored_samples(fault) for fault in faults]
        others = f" after ({counts[0]} before)" if counts[0] != counts[1] else ""
        note = unscored_note(after, run, skip, others=others, faults=faults[1])
        note = note or unscored_note(before, run, skip, faults=faults[0])
        notes += [note] if note else []
    return notes


def effect_loop(problem: Problem, state: State, policy: AcceptancePolicy) -> None:
    """Add the best candidate that passes while one does (at most ``policy.max_effects``)."""
    while len(state.added) < policy.max_effects and state.tried.features:
        current = state.current
        ranked = ranking(problem, current.model, current.inputs, current.scorer, state.tried.features)
        if state.first_ranking is None:
            state.first_ranking = ranked
        guard = DriftGuard(problem.ramp, current.scorer, problem.candidate_values, problem.data[0].time_name)
        stage = "further" if state.added else "first"
        choice = choose(ranked, policy, stage, sensor_columns=state.tried.sensor_columns, drift=guard)
        state.refused += choice.refused
        best = choice.best
        if best is None:
            break
        augment = augment_model if best.over is None else augment_model_over_reference
        state.current = problem.fit(augment(current.model, problem.data, current.inputs, best.feature))
        state.added.append(best)
        state.steps.append(
            Step(best, current.scorer.held_out_rms, state.current.scorer.held_out_rms, choice.alternatives)
        )
        state.tried = replace(
            state.tried, features=[f for f in state.tried.features if f.column != best.feature.column]
        )
        check = state.reference
        if check is not None and droppable_reference(state.current.model, problem.data) is not None:
            # an effect the reference's misfit hid may now be in
            state.current, state.reference = reference_stage(
                problem, state.current, check.reference, after_effects=len(state.added), policy=policy
            )


def result_of(problem: Problem, state: State, *, before, base_check, ambient: tuple[str, ...]) -> DiagnosisResult:
    """The result of the stages."""
    current = state.current.residuals
    time = np.arange(len(before["data"])) * problem.period
    validation_runs = ()
    if "validate" in problem.runs:
        validation_runs = metrics_per_run(
            problem.runs["validate"], problem.skipped["validate"], before["validate"], current["validate"]
        )
    return DiagnosisResult(
        candidates=state.first_ranking or [],
        added=state.added,
        before={key: metrics_of(r) for key, r in before.items()},
        after={key: metrics_of(r) for key, r in current.items()},
        model=state.current.model,
        notes=tuple(state.notes),
        checks_before=residual_checks(before["data"], time),
        checks_after=residual_checks(current["data"], time),
        residuals_before=before,
        residuals_after=current,
        steps=tuple(state.steps),
        refused=tuple(state.refused),
        folds=problem.folds.describe(),
        base_check=base_check,
        run_names={key: joint_name(rs) for key, rs in problem.runs.items()},
        ambient=ambient,
        selection=state.selection,
        reference=state.reference,
        validation_runs=validation_runs,
    )


def as_runs(runs: Run | Sequence[Run] | None) -> list[Run]:
    if runs is None:
        return []
    return [runs] if isinstance(runs, Run) else list(runs)
