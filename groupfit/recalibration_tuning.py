"""Choosing the recalibration filter on held-out data: the model refitted on one part, checks replayed on the next.

The filter's noise cannot be read from the modelling run's own residuals:
they are over-fitted and say nothing about how the error wanders on a new
day. So every candidate is scored as it would serve: the model's coefficients
are refitted on the first part of each modelling run (its inputs, derived
inputs with their whole history, intercept and ridge penalty as the model
has them; a grouped model as one global fit), the rest of the run is
predicted, and checks every T (15, 30, 60, 120 min by default) are replayed
through each candidate filter on that held-out residual. The score is the
mean over the intervals of log(RMS / RMS of the offset hold), the RMS taken
from each stretch's first check on (before it every filter serves alike).

Two things a held-out stretch of the modelling run cannot show are settled
by principle, not by the score. The noise of one check is the part of the
held-out residual no filter can follow: its sample-to-sample scatter
(:func:`white_sigma`), not a free parameter (a filter tuned to distrust its
checks looks good on a quiet stretch and cannot follow a new day's offset).
And a new day may wander more than the stretch did: among the candidates
whose score is within :data:`INDIFFERENCE` of the best (the held-out data do
not tell them apart), the simplest Kalman filter is kept (the fewest terms),
and of those the most responsive (the largest offset noise); the hold, which assumes checks without
noise, only when no Kalman filter comes within that band. Every Kalman candidate applies
a correction only when it stands out of its own noise by
:data:`SIGNIFICANCE_SIGMAS` (:mod:`groupfit.runtime.recalibration`), so a
model at its noise floor is left as it is while an error the checks keep
showing is taken up. The innovation gate is part of every replay (a
candidate whose gate rejects good checks pays for it), and the hold's own
noise is sized so that its gate passes every held-out check with a factor of
two to spare.

A modelling run too short for the longest intervals is scored on the
intervals its held-out stretches hold at least one interval of samples
after the first check for; when none does, the default hold takes its first
check's prior from the model's expected next-run range all the same.

The candidates and their vectorised replay are in
:mod:`groupfit.recalibration_candidates`; :func:`score_candidates` gives the
whole table behind a choice (``bench/bench_recalibration_choice.py`` replays
it on next runs).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from groupfit.fast_response import fit_gains, stage_split
from groupfit.model import ModelFile, Recalibration
from groupfit.model_recalibration import RECALIBRATION_LIMIT
from groupfit.models.ridge import input_spreads, penalty_diagonal, ridge_solve
from groupfit.probe_intervals import whole_samples
from groupfit.recalibration_candidates import GATE_SIGMAS, Candidates, HeldOut, candidate_grid, replay_candidates
from groupfit.runtime.recalibration import DEFAULT_SECTION, default_section, expected_range_high

INTERVALS_S = (900.0, 1800.0, 3600.0, 7200.0)
CUTS = (0.5, 0.7)
"""Each modelling run is refitted on its first 50 % and 70 % and the rest of it predicted."""
INDIFFERENCE = 0.02
"""Held-out scores (mean log RMS ratios) closer than this to the best are not told apart."""
MIN_PROBE_SIGMA_UM = 0.01
GATE_SPARE = 2.0
METHODS = ("auto", "hold", "kalman", "none")
MIN_TRAIN_SAMPLES = 20
DEFAULT_INITIAL_OFFSET_UM = DEFAULT_SECTION["initial_offset_sigma_um"]
"""The prior of a new run's offset in the default hold, unless the model's expected next-run range is wider."""


def held_out_series(model: ModelFile, runs: Sequence, *, cuts: Sequence[float] = CUTS) -> list[HeldOut]:
    """The held-out residual of the model's inputs refitted on the first part of every run.

    ``runs``: (frame, error) pairs, the frame holding the model's columns and
    ``error`` the measured error per row (NaN where not measured).
    """
    series = []
    for frame, error in runs:
        inputs = model.inputs(frame)
        error = np.asarray(error, dtype=float)
        design = np.column_stack([np.ones(len(inputs)), inputs]) if model.intercept else inputs
        for cut in cuts:
            a = int(round(cut * len(design)))
            train = np.isfinite(error[:a])
            if train.sum() < max(MIN_TRAIN_SAMPLES, 2 * design.shape[1]) or a >= len(design) - 1:
                continue
            prediction = _refit_prediction(model, inputs, design, error, a, train)
            series.append(HeldOut(error[a:] - prediction, prediction))
    return series


def _refit_prediction(
    model: ModelFile, inputs: np.ndarray, design: np.ndarray, error: np.ndarray, a: int, train: np.ndarray
) -> np.ndarray:
    """The prediction of the rows from ``a`` on by the model refitted on the rows before ``a`` (``train``: those
    measured); a model with a fast-response stage in its two steps (:mod:`groupfit.fast_response`)."""
    split = stage_split(model)
    if split is None:
        coef = _solve(design[:a][train], error[:a][train], model.ridge_alpha, intercept=model.intercept)
        return design[a:] @ coef
    base, mapping = split
    columns = ([0] if model.intercept else []) + [j + int(model.intercept) for j in base]
    coef = _solve(design[:a][train][:, columns], error[:a][train], model.ridge_alpha, intercept=model.intercept)
    used = np.flatnonzero(np.any(mapping != 0, axis=1))  # only the stage's inputs enter its high-passes
    high = inputs[:, used] @ mapping[used]
    residual = error[:a] - design[:a][:, columns] @ coef
    gains = fit_gains(high[:a], np.where(train, residual, np.nan))
    return design[a:][:, columns] @ coef + high[a:] @ gains


def _solve(design: np.ndarray, target: np.ndarray, alpha: float | None, *, intercept: bool) -> np.ndarray:
    """Least squares, or the ridge penalty as the model was fitted (:mod:`groupfit.models.ridge`: ``alpha · m``
    times each input's squared spread over the rows fitted, the intercept unpenalised)."""
    if not alpha:
        return np.linalg.lstsq(design, target, rcond=None)[0]
    spreads = input_spreads(design[:, 1:] if intercept else design, fit_intercept=intercept)
    return ridge_solve(design, target, penalty_diagonal(spreads, alpha, len(design), fit_intercept=intercept))


def white_sigma(series: Sequence[HeldOut]) -> float:
    """The noise of one check (µm): the held-out residual's sample-to-sample scatter, ``√(½·mean(Δr²))``.

    ``Δr``: the steps between consecutive measured samples (rows without a
    measured error are skipped).
    For a residual that is a slow error plus white noise this is the white
    noise, the part no filter can follow, which a check carries as well.
    """
    steps = np.concatenate([np.diff(s.residual[np.isfinite(s.residual)]) for s in series])
    if not steps.size:
        return MIN_PROBE_SIGMA_UM
    return max(MIN_PROBE_SIGMA_UM, float(np.sqrt(0.5 * np.mean(steps**2))))


@dataclass(frozen=True)
class Tuning:
    """What :func:`choose_recalibration` found: the section and the held-out table behind it."""

    section: Recalibration | None
    intervals_s: tuple[float, ...]
    rms_none_um: float
    rms_hold_um: tuple[float, ...]
    rms_chosen_um: tuple[float, ...]
    rms_none_by_interval_um: tuple[float, ...] = ()
    """Without checks, on the samples each interval's figures are taken from (those after its first check)."""


@dataclass(frozen=True)
class CandidateScores:
    """The held-out table behind a choice (:func:`score_candidates`).

    Attributes
    ----------
    series : list of HeldOut
        The held-out stretches the candidates were replayed on.
    candidates : Candidates or None
        The filters replayed (None when nothing could be scored).
    intervals_s : tuple of float
        The check intervals scored (those the held-out stretches are long enough for).
    left_out_s : tuple of float
        The intervals asked for and not scored.
    rms_um : ndarray, shape (intervals, candidates)
        Held-out RMS of every candidate with a check every interval, from each stretch's first check on.
    chosen : int
        The candidate kept (column of ``rms_um``; 0 is the hold).
    rms_none_um, probe_sigma_um : float
        The held-out RMS without checks and the noise of one check (:func:`white_sigma`); NaN when not measured.
    offset_max_um, rate_um : float
        The correction's bound and rate limit per sample, from the model's switching rule.
    reason : str
        Why nothing could be scored ("" when the table holds).
    """

    series: list[HeldOut]
    candidates: Candidates | None
    intervals_s: tuple[float, ...]
    left_out_s: tuple[float, ...]
    rms_um: np.ndarray
    chosen: int
    rms_none_um: float
    probe_sigma_um: float
    offset_max_um: float
    rate_um: float
    reason: str = ""


def score_candidates(
    model: ModelFile,
    runs: Sequence,
    *,
    method: str = "auto",
    intervals_s: Sequence[float] = INTERVALS_S,
    cuts: Sequence[float] = CUTS,
) -> CandidateScores:
    """Every candidate filter of ``model`` replayed on held-out stretches of its modelling ``runs``, and the one
    :func:`choose_recalibration` keeps (parameters as there; ``method`` "auto", "hold" or "kalman")."""
    intervals = tuple(float(v) for v in intervals_s)
    section = model.switching
    offset_max = float(max(-section.comp_min_um, section.comp_max_um)) if section.comp_max_um else 1000.0
    offset_max = min(offset_max, RECALIBRATION_LIMIT)  # a clamp wider than any thermal error (--range-error)
    rate = min(float(section.rate_limit_um), offset_max) if section.rate_limit_um else offset_max
    period = float(model.sampling_period_s)
    series = held_out_series(model, runs, cuts=cuts)
    empty = CandidateScores(series, None, intervals, (), np.empty((0, 0)), 0, math.nan, math.nan, offset_max, rate)
    if not series:
        return dataclasses.replace(empty, reason="the modelling runs are too short to hold part out")
    residuals = np.concatenate([s.residual for s in series])
    measured = residuals[np.isfinite(residuals)]
    rms_none = float(np.sqrt(np.mean(measured**2))) if measured.size else math.nan
    everies = [whole_samples(t, period) for t in intervals]
    scored = [i for i, every in enumerate(everies) if _scored_span(series, every) >= every]
    if not scored:
        reason = f"the held-out stretches are too short to score a check every {min(intervals) / 60:g} min"
        return dataclasses.replace(empty, rms_none_um=rms_none, reason=reason)
    left_out = tuple(intervals[i] for i in range(len(intervals)) if i not in scored)
    intervals, everies = tuple(intervals[i] for i in scored), [everies[i] for i in scored]
    probe_sigma = white_sigma(series)
    candidates = candidate_grid(
        hold_sigma=_hold_sigma(series, everies, period),
        initial_offset=initial_offset_sigma(model, rms_none, offset_max),
        probe_sigma=probe_sigma,
        method=method,
    )
    rms = np.empty((len(everies), len(candidates)))
    for i, every in enumerate(everies):
        totals = [replay_candidates(s, candidates, every=every, period_s=period) for s in series]
        rms[i] = np.sqrt(sum(t for t, _ in totals) / max(1, sum(n for _, n in totals)))
    table = dataclasses.replace(
        empty, candidates=candidates, intervals_s=intervals, left_out_s=left_out, rms_um=rms, rms_none_um=rms_none
    )
    if not np.all(np.isfinite(rms)) or not np.all(rms[:, 0] > 0):
        return dataclasses.replace(table, reason="the held-out checks leave nothing to compare the filters on")
    best = _most_responsive_of_the_best(
        candidates, np.mean(np.log(rms / rms[:, :1]), axis=0), kalman=method == "kalman"
    )
    return dataclasses.replace(table, chosen=best, probe_sigma_um=probe_sigma)


def choose_recalibration(
    model: ModelFile,
    runs: Sequence,
    *,
    method: str = "auto",
    intervals_s: Sequence[float] = INTERVALS_S,
    cuts: Sequence[float] = CUTS,
) -> Tuning:
    """Choose and tune the recalibration filter of ``model`` on held-out stretches of its modelling ``runs``.

    Parameters
    ----------
    model : ModelFile
    runs : sequence of (frame, error)
        The modelling runs (the frame with the model's columns, the measured error per row).
    method : {"auto", "hold", "kalman", "none"}
        ``auto``: the best on held-out data, the simplest and then the most
        responsive of those the data do not tell apart (the hold only when no
        Kalman filter is among them); ``kalman``: the same among the
        Kalman filters even if the hold does better; ``none``: no section.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if method == "none":
        return Tuning(None, tuple(float(v) for v in intervals_s), math.nan, (), ())
    scores = score_candidates(model, runs, method=method, intervals_s=intervals_s, cuts=cuts)
    offset_max, rate, rms, best = scores.offset_max_um, scores.rate_um, scores.rms_um, scores.chosen
    if scores.reason:
        return _default(
            offset_max,
            rate,
            scores.intervals_s,
            reason=scores.reason,
            initial_offset=initial_offset_sigma(model, scores.rms_none_um, offset_max),
        )
    everies = [whole_samples(t, float(model.sampling_period_s)) for t in scores.intervals_s]
    unchecked = [_rms_unchecked(scores.series, every) for every in everies]
    chosen = {
        "by": "held-out checks",
        "method_asked": method,
        "folds": f"each run refitted on its first {', '.join(f'{100 * c:g} %' for c in cuts)}, the rest predicted",
        "held_out_samples": int(sum(np.sum(np.isfinite(s.residual)) for s in scores.series)),
        "intervals_s": list(scores.intervals_s),
        "rms_none_um": scores.rms_none_um,
        "probe_sigma_um": scores.probe_sigma_um,
        "probe_sigma_from": "the held-out residual's sample-to-sample scatter",
        "indifference": INDIFFERENCE,
        "rms_hold_um": [float(v) for v in rms[:, 0]],
        "rms_chosen_um": [float(v) for v in rms[:, best]],
        "rms_none_by_interval_um": unchecked,
        "candidates": len(scores.candidates),
    }
    if scores.left_out_s:
        chosen["intervals_not_scored_s"] = list(scores.left_out_s)
        chosen["intervals_not_scored_why"] = "held-out stretches too short to score one interval after the first check"
    return Tuning(
        scores.candidates.section(best, offset_max_um=offset_max, rate_um=rate, chosen=chosen),
        scores.intervals_s,
        scores.rms_none_um,
        tuple(float(v) for v in rms[:, 0]),
        tuple(float(v) for v in rms[:, best]),
        tuple(unchecked),
    )


def _scored_span(series: Sequence[HeldOut], every: int) -> int:
    """The samples a replay with a check every ``every`` samples spans from its first check on, over the stretches
    with a measured one there (an error measured on some rows only spans the rows between)."""
    return sum(len(s.residual[every:]) for s in series if np.isfinite(s.residual[every:]).any())


def _rms_unchecked(series: Sequence[HeldOut], every: int) -> float:
    """The held-out RMS without checks over the samples a replay with checks every ``every`` scores."""
    tail = np.concatenate([s.residual[every:] for s in series])
    tail = tail[np.isfinite(tail)]
    return float(np.sqrt(np.mean(tail**2))) if tail.size else math.nan


def initial_offset_sigma(model: ModelFile, rms_none: float, offset_max: float) -> float:
    """The offset a run may start with (µm): the prior of the first check, which sizes its gate.

    A check on a new day may find the model off by what a next run can show,
    not by what the held-out stretches of the modelling run showed: the high
    end of the model's expected next-run range (``training``), at least twice
    the held-out RMS without checks and 1 µm, at most the offset's bound.
    """
    sigma = max(1.0, 2.0 * rms_none if math.isfinite(rms_none) else 0.0, expected_range_high(model))
    return min(sigma, offset_max)


def _most_responsive_of_the_best(candidates: Candidates, score: np.ndarray, *, kalman: bool) -> int:
    """The candidate kept: among those within :data:`INDIFFERENCE` of the best score, the simplest Kalman
    filter (the fewest terms), and of those the most responsive.

    A drift or gain term the held-out data do not ask for only carries the
    checks' noise forward (a gain multiplies it by the prediction). A Kalman
    filter is the more responsive, the larger its offset noise against its
    check noise; on a tie the first. The hold assumes checks without noise,
    which the measured check noise contradicts: it is kept only when no
    Kalman filter comes within the band. ``kalman``: the hold is left out.
    """
    score = np.where(np.arange(len(candidates)) == 0, np.inf, score) if kalman else score
    near = np.flatnonzero(score <= np.min(score) + INDIFFERENCE)
    filters = near[candidates.probe_sigma[near] > 0]
    if not filters.size:
        return int(near[0])
    terms = np.array([len(t) for t in candidates.terms])[filters]
    simplest = filters[terms == terms.min()]
    responsiveness = candidates.offset_sigma[simplest] / candidates.probe_sigma[simplest]
    return int(simplest[np.argmax(responsiveness)])


def _hold_sigma(series: Sequence[HeldOut], everies: Sequence[int], period_s: float) -> float:
    """The hold's offset noise (µm/√h) whose gate passes every held-out change over a check interval twice over."""
    worst = 0.0
    for every in everies:
        hours = every * period_s / 3600.0
        for s in series:
            r = s.residual
            if np.isfinite(r).sum() > every:
                changes = np.abs(r[every:] - r[:-every])
                changes = changes[np.isfinite(changes)]  # between measured samples only
                if changes.size:
                    worst = max(worst, float(changes.max()) / math.sqrt(hours))
    return min(max(1.0, GATE_SPARE * worst / GATE_SIGMAS), RECALIBRATION_LIMIT)


def _default(offset_max: float, rate: float, intervals, *, reason: str, initial_offset: float) -> Tuning:
    """The default hold (:func:`groupfit.runtime.recalibration.default_section`); its first check's prior (and so
    its gate) at least ``initial_offset``."""
    section = default_section(
        offset_max_um=offset_max,
        rate_um_per_sample=rate,
        initial_offset_um=initial_offset,
        chosen={"by": "default", "reason": reason},
    )
    return Tuning(section, intervals, math.nan, (), ())


__all__ = [
    "CUTS",
    "INTERVALS_S",
    "METHODS",
    "HeldOut",
    "CandidateScores",
    "Tuning",
    "choose_recalibration",
    "held_out_series",
    "score_candidates",
    "white_sigma",
]
