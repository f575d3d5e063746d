"""A runtime of the switching rule written from ``groupfit_runtime.json`` alone.

The tests use it to show that the exported JSON table is enough for a
controller to run the rule without the Python package: it reads nothing but
the table (its numbers and the order of its ``steps`` in words) and does not
import ``groupfit.runtime`` or ``groupfit.export``. Its results are compared
with ``groupfit.runtime`` replay, bit for bit.

It implements every format the exporter writes:

* ``groupfit-runtime/1``: readings with valid ranges and a hold of
  ``hold_samples``, the switching windows and criterion, the dot product of
  one group's coefficients, the clamp and the rate limit, the fault bits;
* ``/2``: ``derived_inputs`` (identity, low-pass, derivative, delay), each
  started from the first good reading of its source, and ``inputs`` that
  name a reading or a derived input;
* ``/3``: a power stage ``(|v| / power_scale)^exponent`` (double precision,
  the C library's ``pow``) and a start from rest, and a ``reference`` (a
  reading, or each sensor's first good reading) that every measured input and
  the criterion are taken relative to;
* ``/4``: ``position`` terms (a polynomial in ``P - P0`` whose coefficients
  are again dot products with the inputs, the position clamped to the travel
  and flagged) and a ``dead_band`` (the target held while every measured
  reading is near the band's reference);
* ``/5``: an ``ontime`` derived input (the source's value times its count of
  samples on without a break, times ``scale`` hours);
* ``/7``: a bumpless transfer after a switch: for ``blend_samples`` samples
  the prediction is the new group's plus a closing share of its gap from the
  last output before the switch (``/6``, a blend of the old and the new
  group's predictions, is no longer written and not implemented).

All arithmetic is on Python floats (IEEE double) in the order the steps give
it, so the results are those of any double-precision runtime that performs
the steps as written.
"""

from __future__ import annotations

import math

import numpy as np
from json_probe_runtime import ProbeFilter

FORMATS = tuple(f"groupfit-runtime/{n}" for n in (1, 2, 3, 4, 5, 7))
"""The formats this runtime implements; it refuses any other instead of computing wrongly."""


class TableRuntime:
    """The rule's state, as after a reset, and one sample's steps on it."""

    def __init__(self, table: dict, probes=None):
        if table.get("format") not in FORMATS:
            raise ValueError(f"unknown runtime table format {table.get('format')!r}")
        self.table = table
        self.hold, self.crit = table["hold_samples"], table["criterion_index"]
        self.n_temps, self.n_groups = len(table["temps"]), len(table["coefficients"])
        self.derived = table.get("derived_inputs", [])
        self.reference = table.get("reference")
        self.position, self.dead = table.get("position"), table.get("dead_band")
        self.measured = [source["reading"] for source in table["inputs"] if "reading" in source]
        self.blend_samples = table.get("blend_samples", 0)
        self.count, self.group, self.comp, self.band_target, self.blend = 0, 1, 0.0, 0.0, 0
        self.previous, self.gap, self.has_previous = 0.0, 0.0, False
        n_derived = len(self.derived)
        self.bad, self.last = [self.hold + 1] * self.n_temps, [0.0] * self.n_temps
        self.first, self.has_first = [0.0] * self.n_temps, [False] * self.n_temps
        self.started, self.memory, self.value = [False] * n_derived, [0.0] * n_derived, [0.0] * n_derived
        self.line, self.pos = [[0.0] * d["delay_samples"] for d in self.derived], [0] * n_derived
        self.checks = (
            ProbeFilter(table["recalibration"], (table["comp_min_um"], table["comp_max_um"]))
            if probes is not None
            else None
        )

    def relative(self, m: int) -> float:
        """A measured reading as the model takes it: as read, or minus the reference."""
        if self.reference is None:
            return self.last[m]
        if self.reference["kind"] == "column":
            return self.last[m] - self.last[self.reference["reading"]]
        return self.last[m] - self.first[m]

    def read(self, x: list[float]) -> tuple[bool, bool]:
        """Count, take the valid readings; whether one is held, and whether one is faulty past the hold."""
        table, bad, hold = self.table, self.bad, self.hold
        self.count = min(self.count + 1, table["count_max"])
        for m in range(self.n_temps):
            if table["temp_min_c"][m] <= x[m] <= table["temp_max_c"][m]:
                self.last[m], bad[m] = x[m], 0
            elif bad[m] <= hold:
                bad[m] += 1
        # reference: each measured sensor's first good reading (kind 'start')
        if self.reference is not None and self.reference["kind"] == "start":
            for m in self.measured:
                if not self.has_first[m] and bad[m] == 0:
                    self.first[m], self.has_first[m] = self.last[m], True
        return any(0 < b <= hold for b in bad), any(b > hold for b in bad)

    def derive(self) -> None:
        """The derived inputs, from their source readings as read."""
        for k, d in enumerate(self.derived):
            v = self.last[d["reading"]]
            if d.get("exponent") is not None:  # the power stage, in double precision
                v = math.pow(abs(v) / d["power_scale"], d["exponent"])
            if d["transform"] == "identity":
                self.value[k] = v
                continue
            if not self.started[k] and self.bad[d["reading"]] == 0:
                self.started[k] = True
                s = 0.0 if d.get("start") == "rest" else v
                if d["transform"] == "delay":
                    self.line[k], self.pos[k] = [s] * d["delay_samples"], 0
                else:
                    self.memory[k] = s
            if self.started[k]:
                self.advance(k, d, v)

    def advance(self, k: int, d: dict, v: float) -> None:
        memory, value = self.memory, self.value
        if d["transform"] == "lowpass":
            memory[k] = d["b"] * v + d["a"] * memory[k]
            value[k] = memory[k]
        elif d["transform"] == "derivative":
            value[k], memory[k] = (v - memory[k]) * d["scale"], v
        elif d["transform"] == "ontime":
            memory[k] = memory[k] + 1.0 if v != 0.0 else 0.0
            value[k] = v * (memory[k] * d["scale"])
        else:
            line, pos = self.line[k], self.pos[k]
            value[k], line[pos] = line[pos], v
            self.pos[k] = 0 if pos + 1 == d["delay_samples"] else pos + 1

    def switch(self) -> bool:
        """The next group at its window's end, or within the window when the criterion passes."""
        table, group = self.table, self.group
        if group < self.n_groups:
            window_first, window_last = table["windows"][group - 1]
            direction, threshold = table["directions"][group - 1], table["thresholds_c"][group - 1]
            criterion = self.relative(self.crit)
            if self.count >= window_last:
                self.group += 1
            elif self.count >= window_first and (
                self.bad[self.crit] > self.hold
                or direction == 0
                or (direction > 0 and criterion - threshold >= -table["margin_c"])
                or (direction < 0 and criterion - threshold <= table["margin_c"])
            ):
                self.group += 1
        return self.group != group

    def predict(self, g: int, inputs: list[float]) -> tuple[float, bool]:
        """Group ``g``'s prediction from ``inputs``, its position terms included, and whether P was clamped."""
        row = self.table["coefficients"][g - 1]
        prediction, clamped = row[0], False
        for j, x_j in enumerate(inputs):
            prediction = prediction + row[j + 1] * x_j
        position = self.position
        if position:
            p = self.last[position["reading"]]
            low, high = position["travel_mm"]
            if p < low:
                p, clamped = low, True
            if p > high:
                p, clamped = high, True
            d = p - position["p0_mm"]
            poly = 0.0
            for k in range(position["order"], 0, -1):
                row_k = position["coefficients"][g - 1][k - 1]
                term = row_k[0]
                for j, x_j in enumerate(inputs):
                    term = term + row_k[j + 1] * x_j
                poly = term if k == position["order"] else poly * d + term
            prediction = prediction + poly * d
        return prediction, clamped

    def output(self, switched: bool, *, held: bool) -> tuple[float, float, bool]:
        """Prediction (bumpless transfer, probe correction), the compensation's target, whether P was clamped."""
        inputs = [
            self.relative(source["reading"]) if "reading" in source else self.value[source["derived"]]
            for source in self.table["inputs"]
        ]
        prediction, clamped = self.predict(self.group, inputs)
        if switched and self.has_previous:
            self.gap = self.previous - prediction
            if self.checks:
                self.checks.switched(self.gap)
        if self.blend > 0:
            prediction = prediction + float(self.blend) / float(self.blend_samples + 1) * self.gap
        self.previous, self.has_previous = prediction, True
        target = -prediction
        if self.dead:
            ref = self.last[self.dead["reading"]]
            if any(abs(self.last[m] - ref) > self.dead["threshold_c"] for m in range(self.dead["n_measured"])):
                self.band_target = target
            else:
                target = self.band_target
        if self.checks:  # the model's clamp, then the correction of what the model commands
            command = -target
            target = max(min(target, self.checks.clamp_high), self.checks.clamp_low)
            correction = self.checks.correct(-target, held, command)
            prediction, target = prediction + correction, target - correction
        return prediction, target, clamped

    def step(self, x: list[float]) -> tuple[int, int, float, float]:
        """One sample: ``(code, fault, prediction_um, compensation_um)``."""
        table, bits = self.table, self.table["fault_bits"]
        held, faulted = self.read(x)
        self.derive()
        switched = self.switch()
        if switched:  # the bumpless transfer starts
            self.blend, self.gap = self.blend_samples, 0.0
        clamped = False
        if self.checks:
            self.checks.propagate()
        if faulted:
            prediction = target = 0.0
            if self.checks:
                self.checks.usable = False
            self.has_previous = False
        else:
            prediction, target, clamped = self.output(switched, held=held)
        if self.blend > 0:
            self.blend -= 1
        # clamp, rate limit, output
        low, high = (
            (table["recalibration"]["output_min_um"], table["recalibration"]["output_max_um"])
            if self.checks
            else (table["comp_min_um"], table["comp_max_um"])
        )
        target = max(min(target, high), low)
        delta = max(min(target - self.comp, table["rate_limit_um"]), -table["rate_limit_um"])
        self.comp = self.comp + delta
        fault = held * bits["held"] + faulted * bits["sensor"]
        if clamped:
            fault += bits["position"]
        return (table["sensor_fault_return"] if faulted else self.group, fault, prediction, self.comp)


def run_table(
    table: dict, readings: np.ndarray, probes=None, probe_codes: list | None = None
) -> list[tuple[int, int, float, float]]:
    """Run the rule of ``table`` on ``readings`` from a reset.

    Parameters
    ----------
    table : dict
        The parsed ``groupfit_runtime.json``.
    readings : numpy.ndarray
        One row per sample, one column per entry of ``table["temps"]`` (in that
        order); NaN and infinities are faulty readings.
    probes : numpy.ndarray, optional
        Per sample a probe reading (um), NaN where there is no check; the
        outcome of each check is appended to ``probe_codes``.

    Returns
    -------
    list of tuple
        Per sample ``(code, fault, prediction_um, compensation_um)``: the group
        (1-based) or the sensor-fault return, the fault bits, the prediction
        and the compensation (um).

    Raises
    ------
    ValueError
        If the table's format is not one of :data:`FORMATS`.
    """
    runtime = TableRuntime(table, probes)
    out = []
    for i, x in enumerate(np.asarray(readings, dtype=float).tolist()):
        out.append(runtime.step(x))
        if runtime.checks and not math.isnan(probes[i]):
            probe_codes.append(runtime.checks.probe(float(probes[i])))
    return out


def compensation(table: dict, readings: np.ndarray) -> np.ndarray:
    """The compensation (um) per sample of :func:`run_table`."""
    return np.array([comp for *_, comp in run_table(table, readings)])
