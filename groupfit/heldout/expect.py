"""The error to expect on the next run, per candidate model, the candidate it chooses, and when not to trust it.

``fit``, ``compare`` and ``diagnose`` ask this module; it imports none of them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from groupfit.data import Run
from groupfit.grouping import min_group_size
from groupfit.heldout import calibration
from groupfit.heldout.choice import RMS_TOLERANCE, next_run_choice
from groupfit.heldout.design import shared_columns
from groupfit.heldout.nextrun import (
    LEAVE_ONE_RUN_OUT,
    MIN_SEGMENTS,
    NextRunScores,
    forward_chaining,
    leave_one_run_out,
)
from groupfit.model import ModelFile

CHOICE_RULE = (
    "the simplest model within one standard error, or a factor of "
    f"{RMS_TOLERANCE:g}, of the least expected next-run error"
)


@dataclass(frozen=True)
class NextRunExpectation:
    """Every candidate's expected next-run RMS (calibrated), the chosen one and the notes on trust."""

    scores: NextRunScores
    chosen: int
    """Index into ``scores.candidates``."""
    notes: tuple[str, ...]
    not_tried: tuple = ()
    """The p asked for that were not tried: their groups do not fit in the run before its first scored segment,
    or ``not_tried_reason``."""
    not_tried_reason: str = ""
    """Why ``not_tried`` were not tried, when it is not their groups' length (the run rules them out)."""

    @property
    def candidates(self) -> tuple:
        return self.scores.candidates

    def expected(self, index: int | None = None) -> tuple[float, tuple[float, float]]:
        """The expected RMS (µm) of candidate ``index`` (default: the chosen one) and its range."""
        index = self.chosen if index is None else index
        raw = float(self.scores.raw_rms()[index])
        if self.scores.kind == LEAVE_ONE_RUN_OUT:  # each held-out run is a real next run: no factor
            return calibration.expected_several(raw, np.sqrt(self.scores.sse[index] / self.scores.counts))
        return calibration.expected(raw, unseen_condition=self.scores.unseen_condition)

    def for_candidate(self, candidate) -> tuple[float, tuple[float, float]] | None:
        """The expected RMS and range of the candidate ``candidate`` (e.g. a p), None when it was not scored."""
        if candidate not in self.candidates:
            return None
        return self.expected(self.candidates.index(candidate))

    def choice_among(self, count: int):
        """The candidate the rule of :data:`CHOICE_RULE` chooses among the first ``count`` candidates."""
        mean, error = self.scores.pooled()
        return self.candidates[next_run_choice(mean[:count], error[:count])]

    def method(self) -> str:
        if self.scores.kind == LEAVE_ONE_RUN_OUT:
            low, high = calibration.SEVERAL_RUNS_RANGE
            return (
                f"{self.scores.method()}; range from the best to the worst held-out run, at least "
                f"×{low:.3g}-{high:.3g} (the several-run panel's {calibration.LEVELS[0]:g}th-"
                f"{calibration.LEVELS[1]:g}th percentiles)"
            )
        percentiles = f"{calibration.LEVELS[0]:g}th-{calibration.LEVELS[1]:g}th percentiles"
        if self.scores.unseen_condition:
            return (
                f"{self.scores.method()}; calibrated ×{calibration.UNSEEN_CONDITION_FACTOR:.3g} and ranged by the "
                f"{percentiles} of simulated warm-up/cool-down runs repeated on another day (a scored segment "
                "starts a condition the run before it never saw)"
            )
        return (
            f"{self.scores.method()}; calibrated ×{calibration.FACTOR:.3g}, range from the calibration panel's "
            f"{percentiles}"
        )

    def training(self) -> dict[str, Any]:
        """The model file's ``training`` keys of the chosen candidate's expectation."""
        value, (low, high) = self.expected()
        return {
            "expected_next_run_rms_um": value,
            "expected_next_run_range_um": [low, high],
            "expected_next_run_method": self.method(),
        }

    def model_training(
        self, p: int, choice: NextRunExpectation | None = None, rule: str | None = None
    ) -> dict[str, Any]:
        """The model file's ``training`` keys: this expectation's figures, and how p was chosen (by ``choice``, the
        least-squares candidates' expectation, when it is not this one: a chosen global model got a penalty; by
        ``rule``, in words, when an in-sample rule chose it)."""
        choice = self if choice is None else choice
        data = choice.to_json()
        several = len(choice.candidates) > 1
        only = rule or ("the only p the run allows" if choice.not_tried else "given")
        return {
            **self.training(),
            "model_choice": {
                "p": data["chosen"]["p"] if several else p,
                "rule": data["chosen"]["rule"] if several else only,
                "candidates": data["candidates"],
                "notes": data["notes"],
                **({"not_tried": list(choice.not_tried)} if choice.not_tried else {}),
                **({"not_tried_reason": choice.not_tried_reason} if choice.not_tried_reason else {}),
            },
        }

    def on_measured_rows(self, measured: int, rows: int, pmax: int) -> NextRunExpectation:
        """This expectation of the global model, with p = 1 … ``pmax`` recorded as not tried: the run's error is
        measured on ``measured`` of its ``rows`` rows, and a grouped model's breaks are row indices."""
        if pmax < 1:
            return self
        reason = (
            f"the error is measured on {measured} of {rows} rows, and a grouped model's breaks are row indices "
            "that need it on every row; fill or drop the rows without it to let p >= 1 be tried"
        )
        return dataclasses.replace(self, not_tried=tuple(range(1, pmax + 1)), not_tried_reason=reason)

    def untried(self) -> str:
        """Which p the estimate could not try (their groups do not fit before its first scored segment, or
        ``not_tried_reason``) and what would let them be tried, in words; empty when every p was tried. On a run
        read one sample in k, a longer run is read as sparsely: fewer inputs are the remedy."""
        if not self.not_tried:
            return ""
        listed = ", ".join(str(p) for p in self.not_tried)
        if self.not_tried_reason:
            return f"p = {listed} not tried: {self.not_tried_reason}"
        said = f"p = {listed} not tried, their groups not fitting in the run before its first scored segment"
        if self.scores.stride > 1:
            return (
                f"{said} as the estimate reads it (one sample in {self.scores.stride}); fewer inputs (--select) "
                "would let them be tried"
            )
        return f"{said}; a longer run or fewer inputs (--select) would let them be tried"

    def to_json(self, label: str = "p") -> dict[str, Any]:
        raw = self.scores.raw_rms()
        se = self.scores.standard_error()
        table = []
        for i, candidate in enumerate(self.candidates):
            expected, (lo, hi) = self.expected(i)
            table.append(
                {
                    label: candidate,
                    "expected_next_run_rms_um": expected,
                    "expected_next_run_range_um": [lo, hi],
                    "raw_rms_um": float(raw[i]),
                    "mse_standard_error_um2": float(se[i]) if np.isfinite(se[i]) else None,  # None: one fold
                }
            )
        return {
            **self.training(),
            "chosen": {label: self.candidates[self.chosen], "rule": CHOICE_RULE},
            "candidates": table,
            "notes": list(self.notes),
            **({"not_tried": list(self.not_tried), "not_tried_why": self.untried()} if self.not_tried else {}),
        }

    def candidate_lines(self, run_name: str, marked=None) -> list[str]:
        """Every candidate's expected RMS on one line (``compare``), ``marked`` (fit's choice) marked, the notes."""
        value, (low, high) = self.expected()
        cells = []
        for i, p in enumerate(self.candidates):
            mark = " <- fit's choice" if p == marked else ""
            cells.append(f"p = {p}{' (MLR)' if p == 0 else ''} {self.expected(i)[0]:.3g}{mark}")
        head = (
            f"expected next-run RMS µm from {run_name} alone (range ×{low / value:.2g}-{high / value:.2g}; "
            f"{self.scores.method()}): "
        )
        untried = [f"note: {self.untried()}"] if self.not_tried else []
        return [head + ", ".join(cells), *untried, *(f"note: {note}" for note in self.notes)]

    def line(self) -> str:
        """``expect about X µm RMS on the next run (range a–b; how it was estimated)`` and the notes."""
        value, (low, high) = self.expected()
        text = f"expect  about {value:.3g} µm RMS on the next run (range {low:.3g}-{high:.3g} µm; {self.method()})"
        return "\n".join([text, *(f"note    {note}" for note in self.notes)])


def expect_next_run(
    runs: Sequence[Run],
    p_values: Sequence[int] = (0,),
    *,
    n: int = 3,
    c: float = 3.0,
    fit_intercept: bool = True,
    ridge_alpha: float = 0.0,
    shared: np.ndarray | None = None,
    criterion: str | None = None,
) -> NextRunExpectation:
    """The next-run expectation of every p of ``p_values`` (one run) or of the global model (several runs).

    ``runs`` hold the model's inputs (``temps``, the reference applied) and a
    measured error on every row (:func:`groupfit.data.measured_rows`).
    ``shared``, ``criterion``: a grouped model's inputs with one coefficient
    for every group and its switching sensor (:func:`forward_chaining`).
    """
    if len(runs) > 1:
        n_coef = runs[0].temps.shape[1] + int(fit_intercept)
        min_train = min_group_size(c, n_coef, n)
        scores = leave_one_run_out(runs, fit_intercept=fit_intercept, ridge_alpha=ridge_alpha, min_train=min_train)
    else:
        scores = forward_chaining(
            runs[0],
            list(p_values),
            n=n,
            c=c,
            fit_intercept=fit_intercept,
            ridge_alpha=ridge_alpha,
            shared=shared,
            criterion=criterion,
        )
    chosen = next_run_choice(*scores.pooled())
    not_tried = tuple(p for p in p_values if p not in scores.candidates) if len(runs) == 1 else ()
    return NextRunExpectation(scores, chosen, trust_notes(scores), not_tried)


def expect_for_model(model: ModelFile | Mapping[str, Any], runs: Sequence[Run]) -> NextRunExpectation | None:
    """The expected next-run error of a model file's structure (its inputs, p, penalty, the effects a diagnosis
    added with one coefficient for every group, the switching sensor) refitted on ``runs``.

    ``runs`` as loaded (readings as recorded); the model's inputs, derived ones
    included, are computed from each run's table (:meth:`ModelFile.inputs`). None
    when the estimate cannot be made: a grouped model on several runs, or a run
    too short for the model's groups.
    """
    model = ModelFile.coerce(model)
    if model.p > 0 and len(runs) > 1:
        return None
    prepared = []
    for run in runs:
        inputs = model.inputs(run.frame, run.source)
        rows = np.isfinite(run.error) & np.isfinite(inputs).all(axis=1)
        prepared.append(
            dataclasses.replace(
                run,
                time=run.time[rows],
                temps=inputs[rows],
                temp_names=tuple(model.temps),
                error=run.error[rows],
                frame=run.frame.loc[rows].reset_index(drop=True),
                reference=None,
            )
        )
    try:
        return expect_next_run(
            prepared,
            (model.p,),
            n=model.n,
            c=model.c,
            fit_intercept=model.intercept,
            ridge_alpha=model.ridge_alpha or 0.0,
            shared=shared_columns(model) if model.p > 0 else None,
            criterion=model.switching.criterion if model.p > 0 else None,
        )
    except ValueError:
        return None


def trust_notes(scores: NextRunScores) -> tuple[str, ...]:
    """When the estimate cannot be trusted, and what run to record next."""
    notes = []
    if scores.kind == LEAVE_ONE_RUN_OUT:
        if scores.unfitted_runs:
            notes.append(
                f"{', '.join(scores.unfitted_runs)} not held out: the other runs alone are too short for fit to fit "
                "the model on, so no next run after them can be scored"
            )
        if scores.n_folds < MIN_SEGMENTS:
            notes.append(
                f"only {scores.n_folds} run{'s' if scores.n_folds != 1 else ''} to leave out: a rough estimate; "
                "record another run "
                "(another day or programme) and fit on all of them"
            )
        return tuple(notes)
    if scores.n_conditions == 1:
        notes.append(
            "one run of one operating condition: the estimate only extrapolates this run in time and cannot "
            "see another programme or day; record a run on another condition (another speed programme or "
            "another day) and fit on both (--data A B --p 0)"
        )
    elif scores.leaves_one_condition:
        low, high = calibration.UNSEEN_CONDITION_RATIO_RANGE
        calibrated = (
            "the figure is calibrated on simulated warm-up/cool-down runs repeated on another day, whose next runs "
            f"lay {low:.2g}-{high:.2g} × it (10th-90th percentiles; two heat-then-cool runs of a 3-D printer, each "
            "the other's next run, 0.27 and 0.65 ×)"
            if scores.unseen_condition
            else "the heat law carries the physics model there, and its figure keeps the panel's factor"
        )
        notes.append(
            "a scored segment starts a condition the run before it never saw (a cool-down after the warm-up "
            "alone): every candidate extrapolates there, and that segment weighs most in the figure and the "
            f"choice; {calibrated}; a rough estimate: record a second run and fit on both (--data A B --p 0)"
        )
    elif scores.n_conditions < MIN_SEGMENTS:
        notes.append(
            f"only {scores.n_conditions} operating conditions in the run: the later segments repeat what the "
            "model was fitted on, a rough estimate; record a run with more changes of condition, or a second run"
        )
    if scores.n_folds < MIN_SEGMENTS:
        notes.append(
            f"only {scores.n_folds} segment(s) scored (the last "
            f"{100 * scores.counts.sum() / max(1, scores.n_samples):.0f} % of the run): a rough estimate; "
            "record a longer run, or a second run"
        )
    return tuple(notes)


def penalty_disagreement(penalised: NextRunExpectation, least_squares: NextRunExpectation, alpha: float) -> str:
    """The note when the ridge penalty chosen on held-out operating conditions raises the next-run estimate of
    the global model above least squares' (more than 1 %); empty otherwise. The two checks measure different
    things (a condition the model never saw, a later stretch of the same programme); a next run settles it."""
    plain = least_squares.for_candidate(0)
    if plain is None:
        return ""
    ours, theirs = penalised.expected()[0], plain[0]
    if not ours > 1.01 * theirs:
        return ""
    return (
        f"\nnote    the ridge penalty (alpha {alpha:g}) was chosen on held-out operating conditions, but the next-run "
        f"estimate puts the penalised model above least squares ({ours:.3g} against {theirs:.3g} µm): the two "
        'checks disagree (docs/nextrun.md, "Which model"); --ridge 0 keeps least squares, and a next run replayed '
        "with both settles it"
    )


__all__ = [
    "CHOICE_RULE",
    "NextRunExpectation",
    "penalty_disagreement",
    "expect_for_model",
    "expect_next_run",
    "trust_notes",
]
