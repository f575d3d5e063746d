"""The candidate filters of the held-out tuning (:mod:`groupfit.recalibration_tuning`) and their replay, all at once.

Every candidate runs through one vectorised replay of the filter of
:mod:`groupfit.runtime.recalibration` (double precision, without the
compensation's clamp and rate limit), one column per candidate.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from groupfit.model import Recalibration
from groupfit.probe_intervals import on_measured_rows

SIGNIFICANCE_SIGMAS = 2.0
"""A Kalman candidate applies a correction only beyond this many standard deviations of its estimate."""
GATE_SIGMAS = 5.0
CONFIRM_AFTER = 2


@dataclass(frozen=True)
class HeldOut:
    """One held-out stretch: the refitted model's residual and prediction (µm), NaN where not measured."""

    residual: np.ndarray
    prediction: np.ndarray


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

    ``probe_sigma``: the noise of one check (µm, :func:`groupfit.recalibration_tuning.white_sigma`), the
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


__all__ = [
    "CONFIRM_AFTER",
    "GATE_SIGMAS",
    "SIGNIFICANCE_SIGMAS",
    "Candidates",
    "HeldOut",
    "candidate_grid",
    "replay_candidates",
]
