"""Recalibration from probe checks: the filter the run-time rule runs, in the order every export runs it.

The filter carries up to three states ``x = (offset µm, drift µm/sample, gain)``
and their 3×3 covariance ``P`` (a state the model's ``recalibration`` section
does not list keeps zero variance and stays exactly 0). Per sample, before the
prediction (:meth:`Recalibrator.propagate`)::

    x0 = x0 + x1;  x1 = phi·x1                      (the drift moves the offset and decays)
    A  = F·P:  A0j = P0j + P1j,  A1j = phi·P1j,  A2j = P2j
    P  = A·Fᵀ: Pi0 = Ai0 + Ai1,  Pi1 = Ai1·phi,  Pi2 = Ai2;  Pii = Pii + q_i
    clamp x_i to ±x_max_i

After the model's prediction ``ŷ`` (:meth:`Recalibrator.correct`), with
``m`` what the model commands (``ŷ`` within the rule's clamp), the target
correction ``x0 + x2·m`` (0 while the last applied check left it not
significant, see below); the applied correction ``c`` moves towards it by at
most ``rate`` per sample, and the rule predicts ``ŷ + c``. The compensation
is ``−(m + c)`` within the clamp widened by the offset's bound ``x_max0``
(checks may correct what the clamp leaves; the model alone may not pass it),
then rate-limited. An applied check ``z`` widens the model's clamp to
``2·|z|`` (:meth:`Recalibrator.probe`), within the output's bounds; the
model's command at the check under the widened clamp, ``m'`` (its command
before the clamp, ``u``, clamped anew), replaces ``m``, and the offset takes
the difference, so that the estimate of the error stays where the check put
it (a model held at its clamp and over-predicting is not released by the
check that measured less)::

    t = −u clamped to the widened clamp;  m' = −t
    if m' ≠ m:  x0 = x0 + (1 + x2)·(m − m');  clamp x;  m = m';  significant = true

Under a sensor fault the output is the safe one and ``c`` is left as it is.

A probe check ``z`` (the measured thermal error, µm, after the sample's step;
:meth:`Recalibrator.probe`) is ignored (:data:`PROBE_IGNORED`) before the first
sample, after a sample with a held or faulty reading, or when ``z`` is not a
number within ±:data:`PROBE_LIMIT_UM`. Otherwise, with ``h = (1, 0, m)``::

    nu = (z − m) − (x0 + x2·m)                       (innovation)
    Ph_i = Pi0 + Pi2·m;  hP_j = P0j + P2j·m;  S = hP0 + hP2·m + r
    if not S > 0: ignored
    if nu·nu > gate²·S_gate (below): if rejected-in-a-row < confirm_after: rejected (flagged, nothing changes);
        else (the checks keep disagreeing: a real change) x0 = x0 + nu, P = diag(p0), clamp x: applied
    K_i = Ph_i / S;  x_i = x_i + K_i·nu;  Pij = Pij − K_i·hP_j;  clamp x;
    significant = t·t > sig2·v  with  t = x0 + x2·m,  v = hP0 + hP2·m  (hP of the new P):  applied

A switch of the coefficient vector changes the prediction by the switch's
gap ``g`` (the last output before the switch minus the new group's first
prediction, the gap the bumpless transfer closes): the next check's
innovation carries it, so its gate is widened by it (:meth:`Recalibrator.switched`)::

    at a switch: gap2 = gap2 + g·g
    at a check (after the ignore tests): S_gate = S + gap2, at least p0_0; gap2 = 0;
    the gate compares nu·nu with gate²·S_gate

The gate is never narrower than the prior of a new run's offset (``p0_0 =
initial_offset_sigma_um²``, sized by the model's expected next-run range): a
check is gross only when it is farther from the filter's estimate than a new
run may be off the model. The filter's own innovation variance ``S`` comes
from noise tuned on the quiet modelling run; a next run at speeds it never
saw moves by more between checks, and a gate of ``S`` alone took those moves
for gross readings.

A check taken as a real change leaves the correction significant. With
``sig2 = significance_sigmas² > 0`` a correction the checks do not tell apart
from their own noise (``|t|`` within ``significance_sigmas`` standard
deviations of the estimate) is not applied: a model already at its noise floor
stays as it is, while an error the checks keep showing is taken up as soon as
their average stands out. ``sig2 = 0`` applies every correction.

The hold is the filter with ``x = (offset)``, ``r = 0``: ``K0 = 1``, the
offset becomes the check's residual and its variance 0, growing by ``q0`` per
sample until the next check (so its gate widens with the time since a check).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from groupfit.model import ModelFile, Recalibration
from groupfit.runtime.rate import rate_limited, within

PROBE_APPLIED = 1
PROBE_REJECTED = 0
PROBE_IGNORED = -1
PROBE_LIMIT_UM = 1.0e5
"""A probe reading beyond this (µm) is not a reading (the data's error limit)."""
N_STATES = 3
DEFAULT_SECTION = {
    "method": "hold",
    "terms": ["offset"],
    "offset_sigma_um_per_sqrt_h": 5.0,
    "initial_offset_sigma_um": 10.0,
    "gate_sigmas": 5.0,
    "confirm_after": 2,
    "chosen": {"by": "default: the model file has no recalibration section"},
}
"""The filter of a model without a ``recalibration`` section (bounds from its switching rule)."""


@dataclass(frozen=True)
class RecalTable:
    """The filter's constants, per sample (what every target embeds).

    Attributes
    ----------
    method, terms : as in the section
    q : tuple of 3 float
        Process variance added per sample to offset (µm²), drift ((µm/sample)²), gain.
    phi : float
        Decay of the drift per sample, ``exp(−Δt/τ)``.
    r : float
        Variance of one check (µm²).
    p0 : tuple of 3 float
        Initial variances.
    gate2 : float
        ``gate_sigmas²``.
    significance2 : float
        ``significance_sigmas²`` (0: every correction is applied).
    confirm_after : int
    x_max : tuple of 3 float
        Bounds of offset (µm), drift (µm/sample), gain.
    rate_um : float
        Largest move of the applied correction per sample (µm).
    """

    method: str
    terms: tuple[str, ...]
    q: tuple[float, float, float]
    phi: float
    r: float
    p0: tuple[float, float, float]
    gate2: float
    significance2: float
    confirm_after: int
    x_max: tuple[float, float, float]
    rate_um: float

    @classmethod
    def from_section(cls, section: Recalibration, period_s: float) -> "RecalTable":
        """The per-sample constants of a section at the model's sampling period."""
        h = period_s / 3600.0
        s = section
        return cls(
            method=s.method,
            terms=tuple(s.terms),
            q=(
                s.offset_sigma_um_per_sqrt_h**2 * h,
                s.drift_sigma_um_per_h_per_sqrt_h**2 * h**3,
                s.gain_sigma_per_sqrt_h**2 * h,
            ),
            phi=math.exp(-period_s / (s.drift_tau_h * 3600.0)),
            r=s.probe_sigma_um**2,
            p0=(s.initial_offset_sigma_um**2, (s.initial_drift_sigma_um_per_h * h) ** 2, s.initial_gain_sigma**2),
            gate2=s.gate_sigmas**2,
            significance2=s.significance_sigmas**2,
            confirm_after=int(s.confirm_after),
            x_max=(s.offset_max_um, s.drift_max_um_per_h * h, s.gain_max),
            rate_um=s.rate_um_per_sample,
        )


def expected_range_high(model: ModelFile) -> float:
    """The high end of the model's expected next-run range (``training.expected_next_run_range_um``, µm); 0 when
    the model file has none."""
    bounds = (model.training or {}).get("expected_next_run_range_um") or (0.0, 0.0)
    high = float(bounds[1])
    return high if math.isfinite(high) else 0.0


def default_section(
    *, offset_max_um: float, rate_um_per_sample: float, initial_offset_um: float, chosen: dict | None = None
) -> Recalibration:
    """:data:`DEFAULT_SECTION` bounded by ``offset_max_um`` and ``rate_um_per_sample``, its first check's prior
    (and so its gate) widened to ``initial_offset_um`` within the bound."""
    prior = max(DEFAULT_SECTION["initial_offset_sigma_um"], min(initial_offset_um, offset_max_um))
    return Recalibration(
        **{
            **DEFAULT_SECTION,
            "terms": ("offset",),
            "initial_offset_sigma_um": prior,
            **({"chosen": chosen} if chosen else {}),
        },
        offset_max_um=offset_max_um,
        rate_um_per_sample=rate_um_per_sample,
    )


def model_section(model: ModelFile, *, comp_limit_um: float, rate_limit_um: float) -> Recalibration:
    """The model's section, or the :func:`default_section` bounded by the rule's clamp and rate limit, its first
    check's prior widened to the high end of the model's expected next-run range (:func:`expected_range_high`),
    as a tuned section's is."""
    if model.recalibration is not None:
        return model.recalibration
    return default_section(
        offset_max_um=comp_limit_um, rate_um_per_sample=rate_limit_um, initial_offset_um=expected_range_high(model)
    )


class Recalibrator:
    """The filter's state and its three operations, in double or single precision (``real``: float or float32).

    ``clamp``: the model's clamp ``(low, high)`` of the compensation target (µm), which an applied check
    widens (:meth:`probe`) within ``output``, the bounds of the output.
    """

    def __init__(
        self,
        table: RecalTable,
        real: Any = float,
        *,
        clamp: tuple[float, float] = (-math.inf, math.inf),
        output: tuple[float, float] = (-math.inf, math.inf),
    ):
        self.table = table
        self._real = real
        self._clamp0 = (real(clamp[0]), real(clamp[1]))
        self._output = (real(output[0]), real(output[1]))
        self._q = [real(v) for v in table.q]
        self._p0 = [real(v) for v in table.p0]
        self._phi = real(table.phi)
        self._r = real(table.r)
        self._gate2 = real(table.gate2)
        self._significance2 = real(table.significance2)
        self._max = [real(v) for v in table.x_max]
        self._rate = real(table.rate_um)
        self._limit = real(PROBE_LIMIT_UM)
        self._zero = real(0.0)
        self.reset()

    def reset(self) -> None:
        """No check yet: states 0, initial variances, no correction, no prediction to check against."""
        zero = self._zero
        self.x = [zero] * N_STATES
        self._reset_covariance()
        self.applied = zero
        self.model_um = zero
        self.command_um = zero
        self.usable = False
        self.rejected_in_row = 0
        self.significant = False
        self.gap2 = zero
        self.clamp_low, self.clamp_high = self._clamp0

    def _reset_covariance(self) -> None:
        """``P = diag(p0)``."""
        self.P = [[self._p0[i] if i == j else self._zero for j in range(N_STATES)] for i in range(N_STATES)]

    def _projections(self):
        """``Ph = P·h``, ``hP = hᵀ·P`` and ``S = hP·h + r`` for ``h = (1, 0, m)``."""
        m, P = self.model_um, self.P
        ph = [P[i][0] + P[i][2] * m for i in range(N_STATES)]
        hp = [P[0][j] + P[2][j] * m for j in range(N_STATES)]
        return ph, hp, hp[0] + hp[2] * m + self._r

    def propagate(self) -> None:
        """The time update of one sample (before the prediction)."""
        x, P, phi = self.x, self.P, self._phi
        x[0] = x[0] + x[1]
        x[1] = phi * x[1]
        A = [[P[0][j] + P[1][j] for j in range(N_STATES)], [phi * P[1][j] for j in range(N_STATES)], list(P[2])]
        for i in range(N_STATES):
            P[i] = [A[i][0] + A[i][1], A[i][1] * phi, A[i][2]]
            P[i][i] = P[i][i] + self._q[i]
        self._clamp()

    def switched(self, gap_um) -> None:
        """A switch whose new group's prediction is ``gap_um`` below the last output: the next check's gate
        widens by it, so the change the rule itself made is not taken for a gross reading."""
        self.gap2 = self.gap2 + gap_um * gap_um

    def _clamp(self) -> None:
        for i in range(N_STATES):
            self.x[i] = within(self.x[i], -self._max[i], self._max[i])

    def correct(self, model_um, *, usable: bool = True, command_um=None):
        """The applied correction of this sample, after the model's prediction ``model_um`` (within its clamp;
        ``command_um``: the same before the clamp, default ``model_um``), rate-limited."""
        self.model_um = model_um
        self.command_um = model_um if command_um is None else command_um
        self.usable = usable
        target = self.x[0] + self.x[2] * model_um
        if self._significance2 > self._zero and not self.significant:
            target = self._zero
        self.applied = rate_limited(self.applied, target, self._rate)
        return self.applied

    def invalidate(self) -> None:
        """A sample in sensor fault: no prediction a check could be compared with."""
        self.usable = False

    def innovation(self, measured_um):
        """``(z − m) − (x0 + x2·m)`` against the last sample's prediction ``m``."""
        m = self.model_um
        return (self._real(measured_um) - m) - (self.x[0] + self.x[2] * m)

    def probe(self, measured_um: float) -> int:
        """Fold one check into the state: :data:`PROBE_APPLIED`, :data:`PROBE_REJECTED` or :data:`PROBE_IGNORED`.

        An applied check widens the model's clamp to twice the error it measured (the rule's clamp is twice
        the modelling run's largest prediction), within the output's bounds.
        """
        result = self._check(measured_um)
        if result == PROBE_APPLIED:
            self._widen(self._real(measured_um))
            self._rebase()
        return result

    def _rebase(self) -> None:
        """The model's command at the check under the widened clamp; the offset takes what it changed."""
        model = -within(-self.command_um, self.clamp_low, self.clamp_high)
        if model != self.model_um:
            self.x[0] = self.x[0] + (self._real(1.0) + self.x[2]) * (self.model_um - model)
            self._clamp()
            self.model_um = model
            self.significant = True

    def _widen(self, z) -> None:
        w = -z if z < self._zero else z
        w = w + w
        if w > self.clamp_high:
            self.clamp_high = w if w < self._output[1] else self._output[1]
        if -w < self.clamp_low:
            self.clamp_low = -w if -w > self._output[0] else self._output[0]

    def _check(self, measured_um: float) -> int:
        """The filter's part of :meth:`probe`."""
        z = float(measured_um)
        if not self.usable or not (z >= -PROBE_LIMIT_UM and z <= PROBE_LIMIT_UM):
            return PROBE_IGNORED
        nu = self.innovation(z)
        ph, hp, s = self._projections()
        if not s > self._zero:
            return PROBE_IGNORED
        gate_variance = s + self.gap2
        if gate_variance < self._p0[0]:  # never narrower than a new run's offset
            gate_variance = self._p0[0]
        self.gap2 = self._zero
        if nu * nu > self._gate2 * gate_variance:
            if self.rejected_in_row < self.table.confirm_after:
                self.rejected_in_row += 1
                return PROBE_REJECTED
            # the checks keep disagreeing: a real change, which the offset takes whole (as the hold does)
            self.rejected_in_row = 0
            self.x[0] = self.x[0] + nu
            self._reset_covariance()
            self._clamp()
            self.significant = True
            return PROBE_APPLIED
        self.rejected_in_row = 0
        P = self.P
        gain = [ph[i] / s for i in range(N_STATES)]
        for i in range(N_STATES):
            self.x[i] = self.x[i] + gain[i] * nu
            P[i] = [P[i][j] - gain[i] * hp[j] for j in range(N_STATES)]
        self._clamp()
        self.significant = self._stands_out()
        return PROBE_APPLIED

    def _stands_out(self) -> bool:
        """Whether the target correction ``t = x0 + x2·m`` exceeds ``significance_sigmas`` of its deviation."""
        m = self.model_um
        target = self.x[0] + self.x[2] * m
        _, hp, _ = self._projections()
        return bool(target * target > self._significance2 * (hp[0] + hp[2] * m))


__all__ = [
    "DEFAULT_SECTION",
    "default_section",
    "expected_range_high",
    "PROBE_APPLIED",
    "PROBE_IGNORED",
    "PROBE_LIMIT_UM",
    "PROBE_REJECTED",
    "RecalTable",
    "Recalibrator",
    "model_section",
]
