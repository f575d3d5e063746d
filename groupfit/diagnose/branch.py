"""The two stages that question the model's reference sensor (:mod:`groupfit.diagnose.reference`).

:func:`reference_stage` faces the model on absolute readings with the test
of a change of reference on the held-out folds, before the effects (and
again after each, while the reference stays); :func:`absolute_branch`
diagnoses the model on absolute readings too, when the reference survived,
and faces the two end models with the same test.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

from groupfit.diagnose.candidates import Candidate
from groupfit.diagnose.policy import REFERENCE_NEEDED, REFERENCE_STEADY, AcceptancePolicy, Refusal
from groupfit.diagnose.problem import Fit, Model, Problem
from groupfit.diagnose.reference import absolute_candidate, absolute_model, global_view, steady_reference
from groupfit.diagnose.result import BranchOutcome, DiagnosisResult, ReferenceCheck


def reference_stage(
    problem: Problem, current: Fit, reference: str, *, after_effects: int, policy: AcceptancePolicy
) -> tuple[Fit, ReferenceCheck]:
    """The model refitted on absolute readings when they beat the reference on the held-out folds, else
    ``current``; and the check. A grouped model is judged as one group: the groups' own intercepts absorb the
    level the reference sets."""
    absolute, absolute_inputs = absolute_model(current.model, problem.data)
    grouped = problem.grouped
    given_scorer = problem.scorer(global_view(current.model), current.inputs) if grouped else current.scorer
    judged_scorer = problem.scorer(global_view(absolute) if grouped else absolute, absolute_inputs)
    candidate = absolute_candidate(reference, given_scorer, judged_scorer)
    refusal = policy.refusal(candidate, "reference")
    steady = steady_reference(reference, problem.data) if refusal is None else None
    if steady is not None:
        refusal = Refusal(REFERENCE_STEADY, steady)
    check = ReferenceCheck(
        reference=reference,
        dropped=refusal is None,
        after_effects=after_effects,
        held_out_rms_um={"given": given_scorer.held_out_rms, "absolute": judged_scorer.held_out_rms},
        folds_improved=candidate.n_folds_improved,
        n_folds=problem.folds.n_folds,
        score=candidate.score,
        as_one_group=grouped,
        reason=None if refusal is None else refusal.reason,
        rule_id=None if refusal is None else refusal.rule_id,
    )
    if refusal is not None:
        return current, check
    scorer = problem.scorer(absolute, absolute_inputs) if grouped else judged_scorer
    return Fit(absolute, absolute_inputs, problem.residuals(absolute), scorer), check


def absolute_branch(
    model: Model,
    problem: Problem,
    current: Fit,
    added: list[Candidate],
    check: ReferenceCheck,
    *,
    diagnose_from: Callable[[Model], DiagnosisResult],
    policy: AcceptancePolicy,
) -> tuple[DiagnosisResult | None, ReferenceCheck]:
    """The diagnosis on absolute readings when it beats the one on rises with the effects of each in, else None;
    and the reference check with the outcome (``branch``).

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
    the diagnosis on rises already tried as a lag over the reference.
    """
    reference, scorer = check.reference, current.scorer
    if steady_reference(reference, problem.data) is not None:  # no fold can justify absolute readings
        return None, check
    start, _ = absolute_model(model, problem.data)
    branch = diagnose_from(start)
    branch_scorer = problem.scorer(branch.model, problem.inputs(branch.model))
    candidate = absolute_candidate(reference, scorer, branch_scorer)
    needs_reference = any(c.feature.column == reference for c in branch.added)
    if needs_reference:
        refusal = Refusal(
            REFERENCE_NEEDED,
            f"the effects found on absolute readings include `{reference}` itself: not evidence against it",
        )
    else:
        refusal = policy.refusal(candidate, "reference")
    frees_reference = any(c.feature.column == reference and c.feature.transform == "identity" for c in added)
    as_well = (
        refusal is not None
        and not needs_reference
        and frees_reference
        and policy.as_good_as(candidate, absolute_candidate(reference, scorer, scorer))
    )
    if as_well:
        refusal = None
    outcome = BranchOutcome(
        effects={"given": [c.feature.name for c in added], "absolute": [c.feature.name for c in branch.added]},
        held_out_rms_um={"given": scorer.held_out_rms, "absolute": branch_scorer.held_out_rms},
        folds_improved=candidate.n_folds_improved,
        score=candidate.score,
        as_well_with_fewer_coefficients=as_well,
        reason=None if refusal is None else refusal.reason,
        rule_id=None if refusal is None else refusal.rule_id,
    )
    check = replace(check, branch=outcome)
    if refusal is not None:
        return None, check
    adopted = replace(
        check,
        dropped=True,
        held_out_rms_um=outcome.held_out_rms_um,
        folds_improved=candidate.n_folds_improved,
        score=candidate.score,
        reason=None,
    )
    return replace(branch, reference=adopted), check
