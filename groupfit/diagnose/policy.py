"""Every rule of acceptance of the diagnosis in one place: what an effect must do on held-out folds to be added.

A stage of the diagnosis (a first effect, a further one, an effect chosen
together with the inputs, a change of reference) asks
:meth:`AcceptancePolicy.refusal` about a scored candidate; the answer is
None or a :class:`Refusal` naming the rule (``rule_id``) and saying why in
words. Changing a threshold here changes it for every stage that applies
the rule, and nowhere else. The reasons for each threshold are in the
field's docstring.

Stages
------
``"first"``
    The first effect: the majority test, the worst-fold test, the collinear
    test and the drift guard.
``"further"``
    Every effect after the first: as the first, and it must lower the error
    on *every* held-out fold.
``"joint"``
    An effect chosen together with the inputs (``--select joint``): the test
    of a first effect, and it must remove enough at all.
``"reference"``
    Absolute readings scored like a first effect, against the model on rises
    over its reference: the share of a first effect, without its least RMS
    and its drift guard (the two models differ in a weight, not by a new
    regressor), and never as a transform of the model's own input.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from groupfit.diagnose.candidates import COLLINEAR_R, Candidate, within_one_se
from groupfit.heldout.selection import MIN_GAIN

Stage = Literal["first", "further", "joint", "reference"]

TOO_LITTLE = "too-little"
"""The candidate removes less than the least share or the least RMS of the held-out error."""
OWN_TRANSFORM = "own-transform"
"""A transform of the model's own input, not asked for (``own_transforms``)."""
EVERY_FOLD = "every-fold"
"""A further effect, or a transform of an own input, does not lower the error on every held-out fold."""
COLLINEAR = "collinear"
"""Nearly a copy of a model input, and removes less than twice the least share."""
FOLD_WORSENED = "fold-worsened"
"""One held-out fold's RMS error grows by more than the allowed factor."""
FEW_FOLDS = "few-folds"
"""The error falls on too few of the held-out folds."""
DRIFT = "drift"
"""A straight drift over the run explains the held-out error as well (:mod:`groupfit.diagnose.drift_guard`)."""
REFERENCE_SHARE = "reference-share"
"""Absolute readings remove too little of the held-out error for a change of reference."""
REFERENCE_NEEDED = "reference-needed"
"""The diagnosis on absolute readings took the reference column itself as an effect: no evidence against it."""
REFERENCE_STEADY = "reference-steady"
"""The reference sensor stays within its noise on the modelling run: its folds cannot tell rises over it from
absolute readings, and absolute readings carry the day's air level into every other day."""


@dataclass(frozen=True)
class Refusal:
    """Why a candidate was not accepted: the rule (one of this module's ids) and the reason in words."""

    rule_id: str
    reason: str


@dataclass(frozen=True)
class AcceptancePolicy:
    """The thresholds of acceptance, each with its reason, and the tests built from them."""

    min_score: float = 0.3
    """Least share of the held-out squared error that makes an effect significant."""
    min_effect_rms_um: float = 0.17
    """Least residual RMS (µm) the first effect must remove out of sample: below it, nothing a compensation
    would notice. A low-pass of a heat input that only averages sensor noise removes up to 0.12 µm on the FE run
    with nothing missing and realistic noise (``datasets/diag_none_*``); the floor keeps 1.4 times that."""
    min_further_effect_rms_um: float = 0.2
    """The same for every effect after the first, which explains what is left of a smaller residual (a fifth of
    a typical positioning repeatability); never below ``min_effect_rms_um``."""
    min_folds_improved: float = 0.5
    """Share of held-out folds an effect must improve (more than this); the strict test asks for all of them."""
    max_fold_worsening: float = 2.0
    """No held-out fold's RMS error may grow by more than this factor when the effect is added: an effect that
    fits most conditions at the expense of one is a fit of those conditions, not a cause of the next run."""
    collinear_r: float = COLLINEAR_R
    """A candidate correlated this closely (|r|) with a model input is collinear with it ..."""
    collinear_factor: float = 2.0
    """... and must remove this many times ``min_score``: most of what it adds, the model could already say."""
    max_effects: int = 3
    """Most effects added in one diagnosis."""
    own_transforms: bool = False
    """Whether transforms of the model's own inputs may enter (then under the every-fold test): they re-weight
    information the model has, which fits the modelling conditions and rarely the next run."""
    joint_cluster_r: float = 0.98
    """In the joint selection, inputs correlated above this are one; their representative most correlated with
    the error stands for them."""
    joint_min_gain: float = MIN_GAIN
    """In the joint selection, an input enters while it lowers the held-out squared error by this share (the
    rule of the forward input selection, :data:`groupfit.heldout.selection.MIN_GAIN`)."""

    as_good_standard_errors: float = 1.0
    """Two candidates whose held-out errors differ by less than this many standard errors of their fold-by-fold
    difference are as good as each other: the shorter low-pass, the drift against an effect, the absolute
    readings against a freed reference and the alternatives listed beside a choice are all judged so (the
    one-standard-error rule: what the folds cannot tell apart is decided by simplicity)."""

    def as_good_as(self, candidate: Candidate, best: Candidate) -> bool:
        """Whether the folds cannot tell ``candidate``'s held-out error from ``best``'s."""
        return within_one_se(candidate, best, self.as_good_standard_errors)

    def least_rms(self, stage: Stage) -> float:
        """The least RMS (µm) an effect of ``stage`` must remove."""
        if stage == "further":
            return max(self.min_effect_rms_um, self.min_further_effect_rms_um)
        return self.min_effect_rms_um

    def significant(self, candidate: Candidate, stage: Stage) -> bool:
        """Whether ``candidate`` removes enough of the held-out error to be an effect of ``stage`` at all."""
        return candidate.score >= self.min_score and candidate.explained_rms_um >= self.least_rms(stage)

    def refusal(self, candidate: Candidate, stage: Stage, drift=None) -> Refusal | None:
        """Why ``candidate`` fails the test of ``stage``, or None.

        ``drift``: the :class:`~groupfit.diagnose.drift_guard.DriftGuard` the candidate must be told from (none
        for ``"reference"``). The least share and RMS are tested here only for ``"joint"`` and
        ``"reference"``; the effect loop stops at the first candidate that is not :meth:`significant`.
        """
        if stage == "joint" and not self.significant(candidate, stage):
            return Refusal(TOO_LITTLE, "removes too little of the held-out error")
        if stage == "reference":
            if candidate.score < self.min_score:
                return Refusal(
                    REFERENCE_SHARE,
                    f"removes {100 * candidate.score:.0f} % of the held-out mean-square error; a change of "
                    f"reference needs {100 * self.min_score:.0f} %",
                )
            return self.fold_refusal(candidate, further=False, own_transforms=False)
        refusal = self.fold_refusal(candidate, further=stage == "further", own_transforms=self.own_transforms)
        if refusal is None and drift is not None:
            reason = drift.refusal(candidate, self.min_score, as_good=self.as_good_as)
            refusal = None if reason is None else Refusal(DRIFT, reason)
        return refusal

    def fold_refusal(self, candidate: Candidate, *, further: bool, own_transforms: bool) -> Refusal | None:
        """The tests on the held-out folds, in order: own input, every fold, collinear, worst fold, majority."""
        n_folds = len(candidate.fold_ratios)
        improved = candidate.n_folds_improved
        if candidate.own_input and not own_transforms:
            return Refusal(
                OWN_TRANSFORM,
                "a transform of the model's own input: refused (it re-weights what the model already reads)",
            )
        if (candidate.own_input or further) and improved < n_folds:
            why = "a transform of the model's own input" if candidate.own_input else "a further effect"
            return Refusal(
                EVERY_FOLD,
                f"{why} must lower the error on every held-out fold; it lowers it on {improved} of {n_folds}",
            )
        if candidate.collinearity >= self.collinear_r and candidate.score < self.collinear_factor * self.min_score:
            return Refusal(
                COLLINEAR,
                f"collinear with a model input (|r| {candidate.collinearity:.2f}): it must remove "
                f"{100 * self.collinear_factor * self.min_score:.0f} % of the held-out mean-square error",
            )
        worst = int(np.argmax(candidate.fold_ratios))
        if candidate.fold_ratios[worst] > self.max_fold_worsening**2:
            return Refusal(
                FOLD_WORSENED,
                f"makes one held-out condition (fold {worst + 1}) {np.sqrt(candidate.fold_ratios[worst]):.1f} "
                "times worse (RMS)",
            )
        if candidate.folds_improved <= self.min_folds_improved:
            return Refusal(FEW_FOLDS, f"lowers the error on only {improved} of {n_folds} held-out folds")
        return None


DEFAULT_POLICY = AcceptancePolicy()
