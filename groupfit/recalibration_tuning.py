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

Every candidate runs through one vectorised replay of the filter of
:mod:`groupfit.runtime.recalibration` (double precision, without the
compensation's clamp and rate limit).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from groupfit.fast_response import fit_gains, stage_split
from groupfit.model import ModelFile, Recalibration
from groupfit.model_recalibration import RECALIBRATION_LIMIT
from groupfit.models.ridge import input_spreads, penalty_diagonal, ridge_solve
from groupfit.probe_intervals import on_measured_rows, whole_samples
from groupfit.runtime.recalibration import DEFAULT_SECTION, default_section, expected_range_high

INTERVALS_S = (900.0, 1800.0, 3600.0, 7200.0)
CUTS = (0.5, 0.7)
"""Each modelling run is refitted on its first 50 % and 70 % and the rest of it predicted."""
INDIFFERENCE = 0.02
"""Held-out scores (mean log RMS ratios) closer than this to the best are not told apart."""
SIGNIFICANCE_SIGMAS = 2.0
"""A Kalman candidate applies a correction only beyond this many standard deviations of its estimate."""
MIN_PROBE_SIGMA_UM = 0.01
GATE_SIGMAS = 5.0
CONFIRM_AFTER = 2
GATE_SPARE = 2.0
METHODS = ("auto", "hold", "kalman", "none")
MIN_TRAIN_SAMPLES = 20
DEFAULT_INITIAL_OFFSET_UM = DEFAULT_SECTION["initial_offset_sigma_um"]
"""The prior of a new run's offset in the default hold, unless the model's expected next-run range is wider."""


@dataclass(frozen=True)
class HeldOut:
    """One held-out stretch: the refitted model's residual and prediction (µm), NaN where not measured."""

    residual: np.ndarray
    prediction: np.ndarray


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


@dataclass(frozen=True)
class Candidates:
    """Filters to replay at once: one column per candidate (per-hour units, as the section holds them)."""

    terms: list[tuple[str, ...]]
    offset_sigma: np.ndarray
    drift_sigma: np.ndarray
    drift_tau_h: np.ndarray
    gain_sigma: np.ndarray
    initial_offset: np.ndarray
    initial_drift: np.ndarray
    initial_gain: np.ndarray
    probe_sigma: np.ndarray
    gate_sigmas: np.ndarray
    significance_sigmas: np.ndarray

    def __len__(self) -> int:
        return len(self.terms)

    def section(self, k: int, *, offset_max_um: float, rate_um: float, chosen: dict) -> Recalibration:
        terms = self.terms[k]
        hold = terms == ("offset",) and self.probe_sigma[k] == 0
        return Recalibration(
            method="hold" if hold else "kalman",
            terms=terms,
            offset_sigma_um_per_sqrt_h=float(self.offset_sigma[k]),
            drift_sigma_um_per_h_per_sqrt_h=float(self.drift_sigma[k]),
            drift_tau_h=float(self.drift_tau_h[k]),
            gain_sigma_per_sqrt_h=float(self.gain_sigma[k]),
            initial_offset_sigma_um=float(self.initial_offset[k]),
            initial_drift_sigma_um_per_h=float(self.initial_drift[k]),
            initial_gain_sigma=float(self.initial_gain[k]),
            probe_sigma_um=float(self.probe_sigma[k]),
            gate_sigmas=float(self.gate_sigmas[k]),
            significance_sigmas=float(self.significance_sigmas[k]),
            confirm_after=CONFIRM_AFTER,
            offset_max_um=float(offset_max_um),
            drift_max_um_per_h=float(offset_max_um) if "drift" in terms else 0.0,
            gain_max=1.0 if "gain" in terms else 0.0,
            rate_um_per_sample=float(rate_um),
            chosen=chosen,
        )


def candidate_grid(*, hold_sigma: float, initial_offset: float, probe_sigma: float, method: str = "auto") -> Candidates:
    """The hold (first), then the Kalman filters: offset alone, with a drift, a gain, or both.

    ``probe_sigma``: the noise of one check (µm, :func:`white_sigma`), the
    same for every Kalman candidate; they differ in how the error wanders.
    """
    rows = [(("offset",), hold_sigma, 0.0, 1.0, 0.0, initial_offset, 0.0, 0.0, 0.0, 0.0)]
    if method != "hold":
        drifts = [(s, tau) for s in (0.3, 1.0, 3.0) for tau in (0.5, 2.0, 8.0)]
        gains = [(s, g0) for s in (0.0, 0.02) for g0 in (0.1, 0.3, 1.0)]
        for offset in (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0):
            for drift, gain in itertools.product([None, *drifts], [None, *gains]):
                terms = ("offset",) + (("drift",) if drift else ()) + (("gain",) if gain else ())
                ds, tau = drift or (0.0, 1.0)
                gs, g0 = gain or (0.0, 0.0)
                row = (terms, offset, ds, tau, gs, initial_offset, ds * math.sqrt(tau / 2), g0, probe_sigma)
                rows.append(row + (SIGNIFICANCE_SIGMAS,))
    columns = list(zip(*rows))
    arrays = [np.asarray(c, dtype=float) for c in columns[1:-1]]
    return Candidates(
        list(columns[0]),
        *arrays,
        gate_sigmas=np.full(len(rows), GATE_SIGMAS),
        significance_sigmas=np.array(columns[-1]),
    )


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


def replay_candidates(held: HeldOut, candidates: Candidates, *, every: int, period_s: float) -> tuple[np.ndarray, int]:
    """Sum of squared corrected residuals of every candidate over one stretch, checks every ``every`` samples.

    Returns the sums (one per candidate) and the number of scored samples:
    those after the first check (before it every candidate serves alike).
    """
    c = candidates
    h = period_s / 3600.0
    g = len(c)
    q = np.stack([c.offset_sigma**2 * h, c.drift_sigma**2 * h**3, c.gain_sigma**2 * h])
    phi = np.exp(-period_s / (c.drift_tau_h * 3600.0))
    r = c.probe_sigma**2
    gate2 = c.gate_sigmas**2
    significance2 = c.significance_sigmas**2
    significant = np.zeros(g, dtype=bool)
    offset_max = np.full(g, np.inf)
    x = np.zeros((3, g))
    P = np.zeros((3, 3, g))
    P[0, 0], P[1, 1], P[2, 2] = c.initial_offset**2, (c.initial_drift * h) ** 2, c.initial_gain**2
    P0 = P.copy()
    rejected = np.zeros(g)
    total = np.zeros(g)
    scored = 0
    due = np.arange(every - 1, len(held.residual), every)
    checked = np.zeros(len(held.residual), dtype=bool)
    checked[on_measured_rows(due, np.isfinite(held.residual))] = True  # a check due unmeasured: the next reading
    for k, (res, m) in enumerate(zip(held.residual.tolist(), held.prediction.tolist())):
        x[0] = x[0] + x[1]
        x[1] = phi * x[1]
        A = np.stack([P[0] + P[1], phi * P[1], P[2]])
        P = np.stack([A[:, 0] + A[:, 1], A[:, 1] * phi, A[:, 2]], axis=1)
        P[0, 0] += q[0]
        P[1, 1] += q[1]
        P[2, 2] += q[2]
        if math.isnan(res):
            continue
        target = x[0] + x[2] * m
        served = res - np.where(significant | (significance2 == 0), target, 0.0)
        if k >= every:  # scored from the first check on: before it every filter serves alike
            total += served * served
            scored += 1
        error = res - target
        if not checked[k]:
            continue
        ph = P[:, 0] + P[:, 2] * m
        hp = P[0, :] + P[2, :] * m
        s = hp[0] + hp[2] * m + r
        outside = error * error > gate2 * np.maximum(s, P0[0, 0])
        reject = outside & (rejected < CONFIRM_AFTER)
        fresh = outside & ~reject  # the checks keep disagreeing: the offset takes the change whole
        rejected = np.where(reject, rejected + 1, 0)
        gain = np.where(outside, 0.0, ph / s)
        x = np.clip(x + gain * error, -offset_max, offset_max)
        P = P - gain[:, None, :] * hp[None, :, :]
        if fresh.any():
            x[0] = np.where(fresh, x[0] + error, x[0])
            P = np.where(fresh, P0, P)
        target = x[0] + x[2] * m
        spread = P[0, 0] + P[2, 0] * m + (P[0, 2] + P[2, 2] * m) * m
        significant = np.where(reject, significant, fresh | (target * target > significance2 * spread))
    return total, scored


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
    intervals = tuple(float(v) for v in intervals_s)
    if method == "none":
        return Tuning(None, intervals, math.nan, (), ())
    section = model.switching
    offset_max = float(max(-section.comp_min_um, section.comp_max_um)) if section.comp_max_um else 1000.0
    offset_max = min(offset_max, RECALIBRATION_LIMIT)  # a clamp wider than any thermal error (--range-error)
    rate = min(float(section.rate_limit_um), offset_max) if section.rate_limit_um else offset_max
    period = float(model.sampling_period_s)
    series = held_out_series(model, runs, cuts=cuts)
    if not series:
        return _default(
            offset_max,
            rate,
            intervals,
            reason="the modelling runs are too short to hold part out",
            initial_offset=initial_offset_sigma(model, math.nan, offset_max),
        )
    residuals = np.concatenate([s.residual for s in series])
    measured = residuals[np.isfinite(residuals)]
    rms_none = float(np.sqrt(np.mean(measured**2))) if measured.size else math.nan
    everies = [whole_samples(t, period) for t in intervals]
    scored = [i for i, every in enumerate(everies) if _scored_span(series, every) >= every]
    if not scored:
        return _default(
            offset_max,
            rate,
            intervals,
            reason=f"the held-out stretches are too short to score a check every {min(intervals) / 60:g} min",
            initial_offset=initial_offset_sigma(model, rms_none, offset_max),
        )
    left_out = [intervals[i] for i in range(len(intervals)) if i not in scored]
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
    if not np.all(np.isfinite(rms)) or not np.all(rms[:, 0] > 0):
        return _default(
            offset_max,
            rate,
            intervals,
            reason="the held-out checks leave nothing to compare the filters on",
            initial_offset=initial_offset_sigma(model, rms_none, offset_max),
        )
    best = _most_responsive_of_the_best(
        candidates, np.mean(np.log(rms / rms[:, :1]), axis=0), kalman=method == "kalman"
    )
    unchecked = [_rms_unchecked(series, every) for every in everies]
    chosen = {
        "by": "held-out checks",
        "method_asked": method,
        "folds": f"each run refitted on its first {', '.join(f'{100 * c:g} %' for c in cuts)}, the rest predicted",
        "held_out_samples": int(np.sum(np.isfinite(residuals))),
        "intervals_s": list(intervals),
        "rms_none_um": rms_none,
        "probe_sigma_um": probe_sigma,
        "probe_sigma_from": "the held-out residual's sample-to-sample scatter",
        "indifference": INDIFFERENCE,
        "rms_hold_um": [float(v) for v in rms[:, 0]],
        "rms_chosen_um": [float(v) for v in rms[:, best]],
        "rms_none_by_interval_um": unchecked,
        "candidates": len(candidates),
    }
    if left_out:
        chosen["intervals_not_scored_s"] = left_out
        chosen["intervals_not_scored_why"] = "held-out stretches too short to score one interval after the first check"
    return Tuning(
        candidates.section(best, offset_max_um=offset_max, rate_um=rate, chosen=chosen),
        intervals,
        rms_none,
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
    "Tuning",
    "choose_recalibration",
    "held_out_series",
    "white_sigma",
]
