"""Choose a model's inputs and its missing effects together, on held-out conditions.

A model on many collinear sensors leaves a candidate effect a held-out score
that hardly depends on the effect's time constant: every refit moves all the
collinear coefficients, and they absorb whatever lag the candidate brings.
Choosing the inputs first (``--select forward``) and the effects after fixes
the sensors before the effect can take its share, and a sensor picked to do
the effect's work stays in. Forward selection over both at once lets a heat
law's low-pass and the sensors compete for the same error: each step adds
whichever of them most lowers the held-out error of the model so far.

The two kinds face different tests. A measured input of the model enters
while it lowers the held-out squared error by ``policy.joint_min_gain`` (the rule of
``fit --select forward``); an effect enters only if it passes the test the
diagnosis gives a first effect (stage ``"joint"`` of the
:class:`~groupfit.diagnose.policy.AcceptancePolicy`: the least share of the
held-out error, more than half of the folds improved, no fold more than
doubled, better than a straight drift), so a cause is never admitted on
weaker evidence than the diagnosis asks of it elsewhere. One effect per column. At least one measured input
is kept (the best one, if none lowers the error enough): a compensation
reads temperatures, and its switching criterion is one of them.

The selection is itself fitted to the folds it was scored on.
:meth:`JointProblem.nested_held_out_rms` repeats it with each fold left out
of the choice too: the error to expect of the procedure on a new condition.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from groupfit.diagnose.augment import refit_model
from groupfit.diagnose.candidates import Candidate, score_candidate
from groupfit.diagnose.drift_guard import DriftGuard
from groupfit.diagnose.effects import Tried
from groupfit.diagnose.notes import JOINT, Note
from groupfit.diagnose.policy import AcceptancePolicy
from groupfit.diagnose.problem import Fit, Model, Problem
from groupfit.diagnose.result import InputSelection, Step
from groupfit.features import Feature, derived_matrix
from groupfit.heldout.folds import Folds
from groupfit.heldout.records import OverfitCheck
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.heldout.selection import cluster_representatives, correlation_clusters


@dataclass
class JointSelection:
    """What a joint forward selection chose, in the order it chose it."""

    inputs: list[str] = field(default_factory=list)
    """The measured inputs kept."""
    effects: list[Candidate] = field(default_factory=list)
    """The effects added, each scored against the model chosen before it."""
    order: list[str] = field(default_factory=list)
    """Every name chosen (inputs and effects' feature names), in order."""
    held_out_rms: list[float] = field(default_factory=list)
    """Held-out RMS (µm) of the model before the first choice and after each."""
    first_ranking: list[Candidate] = field(default_factory=list)
    """Every effect scored at the step the first effect entered (or the last step, if none did), best first."""

    def held_out_around(self, effect: Candidate) -> tuple[float, float]:
        """Held-out RMS just before and just after ``effect`` was added."""
        position = self.order.index(effect.feature.name)
        return self.held_out_rms[position], self.held_out_rms[position + 1]


@dataclass(frozen=True)
class JointProblem:
    """A joint forward selection: the error, the candidates and the folds, all on the scored rows.

    Parameters
    ----------
    target : ndarray, shape (N,)
        The measured error on the scored rows.
    inputs : mapping of name to ndarray, shape (N,)
        The model's measured inputs; columns correlated above ``policy.joint_cluster_r`` are one
        (their representative most correlated with the error stands for them).
    effects : sequence of (Feature, ndarray)
        The candidate effects and their values on the same rows.
    folds : Folds
        The held-out folds (whole conditions or runs) on the same rows.
    policy : AcceptancePolicy
        The rules an effect must pass to enter (stage ``"joint"``, with the
        :class:`~groupfit.diagnose.drift_guard.DriftGuard` of the inputs chosen so far) and the joint selection's
        own thresholds.
    drift : ndarray, shape (N,)
        Time since the start of the run: the straight drift an effect must be told from.
    fit_intercept : bool
    """

    target: np.ndarray
    inputs: Mapping[str, np.ndarray]
    effects: Sequence[tuple[Feature, np.ndarray]]
    folds: Folds
    policy: AcceptancePolicy
    drift: np.ndarray
    fit_intercept: bool = True

    def restricted(self, rows: np.ndarray) -> "JointProblem":
        """The same problem on the rows ``rows`` (a boolean mask), their folds only."""
        return JointProblem(
            self.target[rows],
            {name: values[rows] for name, values in self.inputs.items()},
            [(feature, values[rows]) for feature, values in self.effects],
            self.folds.restricted(rows),
            self.policy,
            self.drift[rows],
            self.fit_intercept,
        )

    def select(self) -> JointSelection:
        """Forward selection over the measured inputs and the candidate effects together."""
        target, inputs = self.target, self.inputs
        names = list(inputs)
        if names:
            X = np.column_stack([inputs[n] for n in names])
            clusters = correlation_clusters(X, min_corr=self.policy.joint_cluster_r)
            pool = [names[i] for i in cluster_representatives(X, target, clusters)]
        else:
            pool = []
        remaining = [(f, v) for f, v in self.effects if np.ptp(v) > 0.0]
        values_of = dict(remaining)
        chosen_values: list[np.ndarray] = []
        result = JointSelection()
        while True:
            scorer = HeldOutScorer(target, self.design(chosen_values), self.folds, fit_intercept=self.fit_intercept)
            if not result.held_out_rms:
                result.held_out_rms.append(scorer.held_out_rms)
            best: tuple[Candidate, np.ndarray] | None = None
            null = DriftGuard(self.drift, scorer, lambda c: values_of[c.feature], "drift")
            for name in pool:
                candidate = score_candidate(Feature(name), inputs[name], scorer)
                if candidate.score >= self.policy.joint_min_gain and (best is None or candidate.rank > best[0].rank):
                    best = (candidate, inputs[name])
            scored = [(score_candidate(feature, values, scorer), values) for feature, values in remaining]
            for candidate, values in scored:
                better = best is None or candidate.rank > best[0].rank
                if better and self.policy.refusal(candidate, "joint", null) is None:
                    best = (candidate, values)
            if not result.effects:
                result.first_ranking = sorted((c for c, _ in scored), key=lambda c: -c.rank)
            if best is None and not result.inputs and pool:  # a compensation reads at least one temperature
                best = max(
                    ((score_candidate(Feature(n), inputs[n], scorer), inputs[n]) for n in pool),
                    key=lambda c: c[0].rank,
                )
            if best is None:
                return result
            candidate, values = best
            chosen_values.append(values)
            if candidate.feature.transform == "identity" and candidate.feature.column in pool:
                pool.remove(candidate.feature.column)
                result.inputs.append(candidate.feature.column)
                result.order.append(candidate.feature.column)
            else:
                remaining = [(f, v) for f, v in remaining if f.column != candidate.feature.column]
                result.effects.append(candidate)
                result.order.append(candidate.feature.name)
            result.held_out_rms.append(float(np.sqrt(np.sum(candidate.fold_sse) / len(target))))

    def design(self, columns: Sequence[np.ndarray]) -> np.ndarray:
        """The regressors: the constant (when fitted) and ``columns``."""
        constant = [np.ones(len(self.target))] if self.fit_intercept else []
        if not constant and not columns:
            return np.empty((len(self.target), 0))
        return np.column_stack([*constant, *columns])

    def nested_held_out_rms(self) -> float:
        """Held-out RMS (µm) of the whole procedure: each fold predicted by a selection made without it.

        The selection on the other folds (scored on their own held-out folds),
        fitted by least squares on them, predicts the fold left out.
        """
        values_of = {**self.inputs, **{f.name: v for f, v in self.effects}}
        squared = 0.0
        for train, test in self.folds.splits():
            chosen = self.restricted(train).select()
            design = self.design([values_of[name] for name in chosen.order])
            if design.shape[1] == 0:
                squared += float(self.target[test] @ self.target[test])
                continue
            coef, *_ = np.linalg.lstsq(design[train], self.target[train], rcond=None)
            error = self.target[test] - design[test] @ coef
            squared += float(error @ error)
        return float(np.sqrt(squared / len(self.target)))


@dataclass(frozen=True)
class JointStart:
    """The model refitted on the inputs and first effects chosen together, and what to report of the choice."""

    current: Fit
    selection: InputSelection
    effects: tuple[Candidate, ...]
    first_ranking: list[Candidate]
    steps: tuple[Step, ...]
    notes: tuple[Note, ...]


def joint_start(
    problem: Problem, current: Fit, tried: Tried, policy: AcceptancePolicy, base_check: OverfitCheck
) -> JointStart:
    """Inputs and first effects chosen together (``select_jointly``), the model refitted on them."""
    model = current.model
    temps = model.temps
    causes = [f for f in tried.features if f.column not in tried.sensor_columns and f.column not in temps]
    stacked = np.vstack(current.inputs)[problem.measured]
    values = {name: stacked[:, j] for j, name in enumerate(temps)}
    effects = [(f, problem.values(f)) for f in causes]
    target, intercept = problem.target[problem.measured], bool(model.intercept)
    joint = JointProblem(target, values, effects, problem.folds, policy, problem.ramp, intercept)
    chosen = joint.select()
    refitted = problem.fit(joint_model(problem, model, current.inputs, chosen))
    nested = joint.nested_held_out_rms()
    selection = InputSelection(
        "joint", tuple(chosen.inputs), len(temps), problem.folds.describe(), tuple(chosen.order), nested
    )
    notes = ()
    if nested >= base_check.held_out_rms_um:
        notes = (
            Note(
                JOINT,
                f"the joint selection is not expected to carry to a new condition: chosen again without each "
                f"held-out condition, it predicts it with {nested:.3g} µm RMS, the "
                f"model as given with {base_check.held_out_rms_um:.3g} µm",
            ),
        )
    steps = tuple(Step(c, *chosen.held_out_around(c), joint=True) for c in chosen.effects)
    return JointStart(refitted, selection, tuple(chosen.effects), chosen.first_ranking, steps, notes)


def joint_model(problem: Problem, model: Model, inputs: list[np.ndarray], chosen: JointSelection) -> Model:
    """The model refitted on the inputs and effects chosen together."""
    keep = [model.temps.index(name) for name in chosen.inputs]
    features = [effect.feature for effect in chosen.effects]
    period = model.sampling_period_s
    runs = problem.data
    columns = [
        np.column_stack([x[:, keep], derived_matrix(features, r.frame, period, r.source)]) for x, r in zip(inputs, runs)
    ]
    return refit_model(model, runs, columns, [*chosen.inputs, *(f.name for f in features)], features)
