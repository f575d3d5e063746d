"""The run-time rule, sample by sample: the reference interpreter every export agrees with.

Precision: double, or IEEE single precision operation for operation (numpy
float32 scalars) as the C build with ``GF_USE_FLOAT`` and a PLC's REAL compute.
One step is the same in both: the power stage of a derived input,
``(|v| / scale)^exponent``, is computed in double precision with
:func:`math.pow` (which calls the C library's ``pow``, as the C export does;
not numpy's power, whose vector loops may round differently), from the
source's value widened to double; single precision rounds its result to
float32 once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.runtime.period import at_period
from groupfit.runtime.rate import rate_limited, within
from groupfit.runtime.recalibration import PROBE_APPLIED, PROBE_IGNORED, PROBE_REJECTED, Recalibrator
from groupfit.runtime.rule import (
    COUNT_MAX,
    FAULT_HELD,
    FAULT_POSITION,
    FAULT_SENSOR,
    RETURN_SENSOR_FAULT,
    SWITCH_CRITERION,
    SWITCH_FORCED,
    SWITCH_NONE,
)
from groupfit.runtime.state import restore
from groupfit.runtime.tables import RuleTables

PROBE_CODE_OFFSET = 2
""":attr:`Replay.probe` holds a check's return plus this (1 ignored, 2 rejected, 3 applied), 0 without a check."""


@dataclass(frozen=True)
class StepResult:
    """What the rule decides for one sample."""

    group: int
    """1-based group serving this sample (tracked through faults too)."""
    prediction_um: float
    """Predicted thermal error (0 under a sensor fault)."""
    compensation_um: float
    """Value for the controller: −prediction, clamped and rate-limited."""
    fault: int
    """Bit mask: :data:`FAULT_HELD` (1), :data:`FAULT_SENSOR` (2)."""
    switched: int = SWITCH_NONE
    """0, or :data:`SWITCH_CRITERION` / :data:`SWITCH_FORCED` when the group advanced at this sample."""
    target_um: float = 0.0
    """What the compensation moves towards: after the clamps, before the rate limit."""
    clamped: bool = False
    """Whether a clamp held the target short of −prediction (the model's clamp or the output's)."""

    @property
    def code(self) -> int:
        """What the exported step routines return: the group, or :data:`RETURN_SENSOR_FAULT`."""
        return RETURN_SENSOR_FAULT if self.fault & FAULT_SENSOR else self.group


@dataclass(frozen=True)
class Replay:
    """A run replayed sample by sample (arrays of length N)."""

    group: np.ndarray
    prediction_um: np.ndarray
    compensation_um: np.ndarray
    fault: np.ndarray
    switched: np.ndarray
    probe: np.ndarray | None = None
    """Per sample: 0 without a check, else :data:`PROBE_CODE_OFFSET` plus what the probe returned."""
    target_um: np.ndarray | None = None
    """Per sample: :attr:`StepResult.target_um`."""
    clamped: np.ndarray | None = None
    """Per sample: :attr:`StepResult.clamped`."""

    def probe_counts(self) -> dict[str, int]:
        """Checks applied, rejected by the gate and ignored (no valid prediction)."""
        code = np.zeros(len(self.group), dtype=int) if self.probe is None else self.probe - PROBE_CODE_OFFSET
        has = np.zeros(len(self.group), dtype=bool) if self.probe is None else self.probe != 0
        return {
            "applied": int(np.sum(has & (code == PROBE_APPLIED))),
            "rejected": int(np.sum(has & (code == PROBE_REJECTED))),
            "ignored": int(np.sum(has & (code == PROBE_IGNORED))),
        }

    def tail(self, start: int) -> "Replay":
        """The samples from 0-based ``start`` on (a run replayed with its history in front)."""
        fields = (self.group, self.prediction_um, self.compensation_um, self.fault, self.switched)
        extra = {
            name: None if getattr(self, name) is None else getattr(self, name)[start:]
            for name in ("probe", "target_um", "clamped")
        }
        return Replay(*(array[start:] for array in fields), **extra)

    def switch_samples(self) -> list[dict[str, int | bool]]:
        """Every switch: 1-based sample, groups before and after, whether it was forced."""
        out = []
        for i in np.flatnonzero(self.switched):
            out.append(
                {
                    "i": int(i) + 1,
                    "from": int(self.group[i]) - 1,
                    "to": int(self.group[i]),
                    "forced": bool(self.switched[i] == SWITCH_FORCED),
                }
            )
        return out


class SwitchingRule:
    """The run-time rule: one call of :meth:`step` per sample.

    Parameters
    ----------
    model : ModelFile or model file object
    precision : {"double", "single"}
        Double, or IEEE single precision computed operation for operation as
        the C build with ``GF_USE_FLOAT`` and a PLC's REAL compute it.
    period_s : float, optional
        The live run's sampling period. Outside the model's
        ``period_tolerance`` the model is rescaled to it
        (:func:`groupfit.runtime.period.at_period`: a model without breaks
        runs at any period, its lags keep their time constants) or refused
        (InputError) when its counts cannot be rescaled.
    """

    def __init__(
        self, model: ModelFile | Mapping[str, Any], *, precision: str = "double", period_s: float | None = None
    ):
        if precision not in ("double", "single"):
            raise ValueError(f"precision must be 'double' or 'single', got {precision!r}")
        if period_s is not None:
            model = at_period(model, period_s)
        self.tables = RuleTables.from_model(model)
        self.precision = precision
        real = np.float32 if precision == "single" else float
        t = self.tables
        self._real = real
        with np.errstate(over="ignore"):  # a limit beyond single precision's range is +-inf there
            self._valid = [(real(low), real(high)) for low, high in zip(t.valid_min, t.valid_max)]
        self._coef = [[real(v) for v in row] for row in t.coefficients]
        self._threshold = [real(v) for v in t.thresholds_c]
        self._margin = real(t.margin_c)
        self._out_min = real(t.output_min_um)
        self._out_max = real(t.output_max_um)
        self._rate = real(t.rate_limit_um)
        self._zero = real(0.0)
        self._lp_a = [real(d.a) for d in t.derived]
        self._lp_b = [real(d.b) for d in t.derived]
        self._scale = [real(d.scale) for d in t.derived]
        self._one = real(1.0)
        if t.has_position:
            self._pcoef = [[[real(v) for v in row] for row in group] for group in t.position_coefficients]
            self._p0 = real(t.p0_mm)
            self._travel_min = real(t.travel_min_mm)
            self._travel_max = real(t.travel_max_mm)
        self._band = real(t.dead_band_c)
        self.recal = Recalibrator(
            t.recalibration,
            real,
            clamp=(t.comp_min_um, t.comp_max_um),
            output=(t.output_min_um, t.output_max_um),
        )
        self.reset()

    def reset(self) -> None:
        """Back to the first sample: group 1, no good readings yet, derived inputs not started, compensation 0."""
        t = self.tables
        self.count = 0
        self.group = 1
        self.bad = [t.hold_samples + 1] * t.n_temps
        self.last = [self._zero] * t.n_temps
        self.compensation = self._zero
        self.started = [False] * len(t.derived)
        self.memory = [self._zero] * len(t.derived)
        self.derived = [self._zero] * len(t.derived)
        self.lines = [[self._zero] * d.delay_samples for d in t.derived]
        self.positions = [0] * len(t.derived)
        self.band_target = self._zero
        self.blend = 0
        self.gap = self._zero
        self.previous = self._zero
        self.has_previous = False
        self.k0 = self._zero
        self.slope = self._zero
        self.recal.reset()
        self._reset_reference()

    def step(self, readings: Sequence[float]) -> StepResult:
        """Process one sample of readings (the model's measured inputs, then the sources, see :attr:`tables`)."""
        t = self.tables
        if len(readings) != t.n_temps:
            raise InputError(f"{len(readings)} readings given; the model takes {t.n_temps} ({', '.join(t.raw_names)})")
        if self.count < COUNT_MAX:
            self.count += 1
        held, faulted = self._read(readings)
        self._reference_step()
        for k in range(len(t.derived)):
            self._derive(k)
        switched = self._switch()
        clamped = model_clamped = False
        self.recal.propagate()
        if faulted:
            prediction = self._zero
            target = self._zero
            self.recal.invalidate()
            self.has_previous = False
        else:
            prediction, target, clamped, model_clamped = self._predict(switched, held=held)
        if self.blend > 0:
            self.blend -= 1
        wanted = target
        target = within(target, self._out_min, self._out_max)
        self.compensation = rate_limited(self.compensation, target, self._rate)
        fault = (FAULT_HELD if held else 0) + (FAULT_SENSOR if faulted else 0) + (FAULT_POSITION if clamped else 0)
        limited = bool(target != wanted or model_clamped)
        return StepResult(
            self.group, float(prediction), float(self.compensation), fault, switched, float(target), limited
        )

    def _read(self, readings: Sequence[float]) -> tuple[bool, bool]:
        """Take the valid readings, hold the last good value of an invalid one; whether a reading is held, and
        whether one has been invalid for longer than the hold (a sensor fault)."""
        t = self.tables
        held = faulted = False
        values = [float(readings[m]) for m in range(t.n_temps)]
        if self.precision == "single":  # each reading rounded before its range is tested, as a REAL input is
            with np.errstate(over="ignore"):
                values = [self._real(v) for v in values]
        for m, reading in enumerate(values):
            low, high = self._valid[m]
            if reading >= low and reading <= high:
                self.last[m] = reading
                self.bad[m] = 0
            elif self.bad[m] <= t.hold_samples:
                self.bad[m] += 1
            if self.bad[m] > t.hold_samples:
                faulted = True
            elif self.bad[m] > 0:
                held = True
        return held, faulted

    def _switch(self) -> int:
        """Move to the next group when its window is reached and the criterion passes, or at the window's end."""
        t = self.tables
        switched = SWITCH_NONE
        if self.group < t.n_groups:
            w = self.group - 1
            if self.count >= t.window_last[w]:
                self.group += 1
                switched = SWITCH_FORCED
            elif self.count >= t.window_first[w] and self._criterion_passes(w):
                self.group += 1
                switched = SWITCH_CRITERION
        if switched:
            self.blend = t.blend_samples
            self.gap = self._zero
        return switched

    def _predict(self, switched: int, *, held: bool):
        """The prediction (bumpless transfer and probe correction included), the compensation's target, whether
        the position was clamped, and whether the model's clamp bound its command."""
        t = self.tables
        prediction, clamped = self._group_prediction(self.group)
        if switched and self.has_previous:  # bumpless transfer: the gap from the last output to the new group
            self.gap = self.previous - prediction
            self.recal.switched(self.gap)
        if self.blend > 0:  # closed by one share of blend_samples + 1 per sample
            share = self._real(self.blend) / self._real(t.blend_samples + 1) * self.gap
            prediction = prediction + share
            if t.has_position:  # carried by K0, so that K0 + tan(beta)·(P − P0) stays the output
                self.k0 = self.k0 + share
        self.previous = prediction
        self.has_previous = True
        target = -prediction
        if t.has_dead_band:
            if self._outside_dead_band():
                self.band_target = target
            else:
                target = self.band_target
        served = within(target, self.recal.clamp_low, self.recal.clamp_high)  # the model alone commands no more
        # checks correct what the model commands
        correction = self.recal.correct(-served, usable=not held, command_um=-target)
        return prediction + correction, served - correction, clamped, served != target

    def _group_prediction(self, group: int):
        """The prediction of 1-based ``group`` from the current inputs (position terms included), and whether
        the position was clamped."""
        t = self.tables
        row = self._coef[group - 1]
        prediction = row[0]
        for j in range(t.n_inputs):
            r = t.input_reading[j]
            value = self._value(r) if r >= 0 else self.derived[t.input_derived[j]]
            prediction = prediction + row[j + 1] * value
        if t.has_position:
            return self._position_terms(prediction, group)
        return prediction, False

    def _position_terms(self, prediction, group: int):
        """``K0 + c_1·d + … + c_K·d^K`` (Horner, highest power first), ``d = P − P0``, P clamped to the travel.

        Also keeps ``k0`` (the position-free part) and ``slope`` (``c_1``, µm per
        mm: tanβ of a first-order model) for the controller's SD43900/SD43910.
        """
        t = self.tables
        position = self.last[t.position_reading]
        clamped = False
        if position < self._travel_min:
            position = self._travel_min
            clamped = True
        if position > self._travel_max:
            position = self._travel_max
            clamped = True
        d = position - self._p0
        rows = self._pcoef[group - 1]
        poly = self._zero
        for k in range(t.position_order - 1, -1, -1):
            row = rows[k]
            term = row[0]
            for j in range(t.n_inputs):
                r = t.input_reading[j]
                value = self._value(r) if r >= 0 else self.derived[t.input_derived[j]]
                term = term + row[j + 1] * value
            poly = term if k == t.position_order - 1 else poly * d + term
            if k == 0:
                self.slope = term
        self.k0 = prediction
        return prediction + poly * d, clamped

    def _outside_dead_band(self) -> bool:
        """Whether some measured input differs from the dead band's reference by more than the band."""
        t = self.tables
        ref = self.last[t.dead_band_reading]
        for m in range(t.n_measured):
            difference = self.last[m] - ref
            if difference < self._zero:
                difference = -difference
            if difference > self._band:
                return True
        return False

    def _derive(self, k: int) -> None:
        """Advance derived input ``k`` by one sample from its source's last good value.

        The value ``x`` is the source's last good reading, or its power stage
        (in double precision, rounded to the rule's precision once). A rest
        start begins a low-pass or delay from a zero state at the source's
        first good reading, a steady start from ``x``.
        """
        d = self.tables.derived[k]
        x = self.last[d.reading]
        if d.has_power:
            x = self._real(d.power(float(x)))
        if d.transform == "identity":
            self.derived[k] = x
            return
        if not self.started[k] and self.bad[d.reading] == 0:
            self.started[k] = True
            initial = self._zero if d.from_rest else x
            if d.transform == "delay":
                self.lines[k] = [initial] * d.delay_samples
                self.positions[k] = 0
            else:
                self.memory[k] = initial  # a derivative always starts steady (its start is "steady")
        if not self.started[k]:
            return
        if d.transform == "lowpass":
            self.memory[k] = self._lp_b[k] * x + self._lp_a[k] * self.memory[k]
            self.derived[k] = self.memory[k]
        elif d.transform == "derivative":
            self.derived[k] = (x - self.memory[k]) * self._scale[k]
            self.memory[k] = x
        elif d.transform == "ontime":  # memory: the samples the source has been on without a break
            self.memory[k] = self.memory[k] + self._one if x != self._zero else self._zero
            self.derived[k] = x * (self.memory[k] * self._scale[k])
        else:
            line, position = self.lines[k], self.positions[k]
            self.derived[k] = line[position]
            line[position] = x
            position += 1
            if position >= d.delay_samples:
                position = 0
            self.positions[k] = position

    def input_values(self) -> list[float]:
        """The model's inputs at the last sample: held readings and derived inputs."""
        t = self.tables
        return [
            float(self._value(r) if r >= 0 else self.derived[t.input_derived[j]]) for j, r in enumerate(t.input_reading)
        ]

    def _criterion_passes(self, w: int) -> bool:
        t = self.tables
        c = t.criterion_reading
        direction = t.directions[w]
        if self.bad[c] > t.hold_samples or direction == 0:
            return True
        difference = self._value(c) - self._threshold[w]
        if direction > 0:
            return bool(difference >= -self._margin)
        return bool(difference <= self._margin)

    # ----------------------------------------------------------------- reference temperature

    def _reset_reference(self) -> None:
        """No first reading yet (``start`` reference)."""
        n_temps = self.tables.n_temps
        self.first = [self._zero] * n_temps
        self.has_first = [False] * n_temps

    def _reference_step(self) -> None:
        """``start`` reference: keep every measured sensor's first good reading since the reset."""
        t = self.tables
        if not t.reference_start:
            return
        for m in range(t.n_measured):
            if not self.has_first[m] and self.bad[m] == 0:
                self.first[m] = self.last[m]
                self.has_first[m] = True

    def _value(self, r: int):
        """Measured reading ``r`` as the model takes it: its last good value, minus the reference."""
        t = self.tables
        if t.reference_reading >= 0:
            return self.last[r] - self.last[t.reference_reading]
        if t.reference_start:
            return self.last[r] - self.first[r]
        return self.last[r]

    def probe(self, measured_error_um: float) -> int:
        """A probe check after the last :meth:`step`: the measured thermal error (µm), folded into the correction.

        Returns :data:`~groupfit.runtime.recalibration.PROBE_APPLIED`,
        ``PROBE_REJECTED`` (the innovation gate; nothing changes) or
        ``PROBE_IGNORED`` (no valid prediction at that sample, or not a reading).
        """
        return self.recal.probe(measured_error_um)

    def replay(self, readings, probes=None, state=None) -> Replay:
        r"""Reset (to ``state``, a :func:`groupfit.runtime.state.capture`\ d one, when given), then step through
        every row of an (N, k) array of readings.

        ``probes``: optional length-N array of probe readings (µm), NaN where
        there is no check; a check at row i follows row i's step.
        """
        readings = np.asarray(readings, dtype=float)
        if readings.ndim != 2 or readings.shape[1] != self.tables.n_temps:
            raise InputError(
                f"readings of shape {readings.shape}: the model takes {self.tables.n_temps} columns "
                f"({', '.join(self.tables.raw_names)})"
            )
        self.reset()
        if state is not None:
            restore(self, state)
        n_samples = len(readings)
        group = np.empty(n_samples, dtype=int)
        target = np.empty(n_samples)
        clamped = np.zeros(n_samples, dtype=bool)
        fault = np.empty(n_samples, dtype=int)
        switched = np.empty(n_samples, dtype=int)
        prediction = np.empty(n_samples)
        compensation = np.empty(n_samples)
        checks = None if probes is None else np.asarray(probes, dtype=float).tolist()
        probe_code = np.zeros(n_samples, dtype=int)
        for i, row in enumerate(readings.tolist()):
            result = self.step(row)
            group[i], fault[i], switched[i] = result.group, result.fault, result.switched
            prediction[i], compensation[i] = result.prediction_um, result.compensation_um
            target[i], clamped[i] = result.target_um, result.clamped
            if checks is not None and not math.isnan(checks[i]):
                probe_code[i] = PROBE_CODE_OFFSET + self.probe(checks[i])
        return Replay(group, prediction, compensation, fault, switched, probe_code, target, clamped)


def check_period(tables: RuleTables, period_s: float) -> None:
    """Refuse a live sampling period that differs from the model's."""
    if not (abs(period_s - tables.sampling_period_s) <= tables.period_tolerance_s):
        raise InputError(
            f"sampling period {period_s:g} s differs from the model's {tables.sampling_period_s:g} s "
            f"(tolerance {100 * tables.period_tolerance:g} %): the rule counts samples, so resample the run "
            "to the model's period or fit a model at this period"
        )
