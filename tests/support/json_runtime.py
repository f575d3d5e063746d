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
    if table.get("format") not in FORMATS:
        raise ValueError(f"unknown runtime table format {table.get('format')!r}")
    hold, crit = table["hold_samples"], table["criterion_index"]
    n_temps, n_groups = len(table["temps"]), len(table["coefficients"])
    bits = table["fault_bits"]
    derived = table.get("derived_inputs", [])
    reference = table.get("reference")
    position, dead = table.get("position"), table.get("dead_band")
    measured = [source["reading"] for source in table["inputs"] if "reading" in source]

    # state, as after a reset
    count, group, comp, band_target, blend = 0, 1, 0.0, 0.0, 0
    previous, gap, has_previous = 0.0, 0.0, False
    blend_samples = table.get("blend_samples", 0)
    bad, last = [hold + 1] * n_temps, [0.0] * n_temps
    first, has_first = [0.0] * n_temps, [False] * n_temps
    started, memory, value = [False] * len(derived), [0.0] * len(derived), [0.0] * len(derived)
    line, pos = [[0.0] * d["delay_samples"] for d in derived], [0] * len(derived)

    def relative(m: int) -> float:
        """A measured reading as the model takes it: as read, or minus the reference."""
        if reference is None:
            return last[m]
        if reference["kind"] == "column":
            return last[m] - last[reference["reading"]]
        return last[m] - first[m]

    checks = ProbeFilter(table["recalibration"]) if probes is not None else None
    out = []
    for i, x in enumerate(np.asarray(readings, dtype=float).tolist()):
        # count and readings
        count = min(count + 1, table["count_max"])
        for m in range(n_temps):
            if table["temp_min_c"][m] <= x[m] <= table["temp_max_c"][m]:
                last[m], bad[m] = x[m], 0
            elif bad[m] <= hold:
                bad[m] += 1
        faulted = any(b > hold for b in bad)
        held = any(0 < b <= hold for b in bad)

        # reference: each measured sensor's first good reading (kind 'start')
        if reference is not None and reference["kind"] == "start":
            for m in measured:
                if not has_first[m] and bad[m] == 0:
                    first[m], has_first[m] = last[m], True

        # derived inputs, from their source readings as read
        for k, d in enumerate(derived):
            v = last[d["reading"]]
            if d.get("exponent") is not None:  # the power stage, in double precision
                v = math.pow(abs(v) / d["power_scale"], d["exponent"])
            if d["transform"] == "identity":
                value[k] = v
                continue
            if not started[k] and bad[d["reading"]] == 0:
                started[k] = True
                s = 0.0 if d.get("start") == "rest" else v
                if d["transform"] == "delay":
                    line[k], pos[k] = [s] * d["delay_samples"], 0
                else:
                    memory[k] = s
            if started[k]:
                if d["transform"] == "lowpass":
                    memory[k] = d["b"] * v + d["a"] * memory[k]
                    value[k] = memory[k]
                elif d["transform"] == "derivative":
                    value[k], memory[k] = (v - memory[k]) * d["scale"], v
                elif d["transform"] == "ontime":
                    memory[k] = memory[k] + 1.0 if v != 0.0 else 0.0
                    value[k] = v * (memory[k] * d["scale"])
                else:
                    value[k], line[k][pos[k]] = line[k][pos[k]], v
                    pos[k] = 0 if pos[k] + 1 == d["delay_samples"] else pos[k] + 1

        # switching
        before = group
        if group < n_groups:
            window_first, window_last = table["windows"][group - 1]
            direction, threshold = table["directions"][group - 1], table["thresholds_c"][group - 1]
            if count >= window_last:
                group += 1
            elif count >= window_first and (
                bad[crit] > hold
                or direction == 0
                or (direction > 0 and relative(crit) - threshold >= -table["margin_c"])
                or (direction < 0 and relative(crit) - threshold <= table["margin_c"])
            ):
                group += 1

        if group != before:  # the bumpless transfer starts
            blend, gap = blend_samples, 0.0

        # prediction, position terms, dead band
        clamped = False
        if checks:
            checks.propagate()
        if faulted:
            prediction = target = 0.0
            if checks:
                checks.usable = False
        else:
            inputs = [
                relative(source["reading"]) if "reading" in source else value[source["derived"]]
                for source in table["inputs"]
            ]

            def predict(g: int, inputs=inputs) -> tuple[float, bool]:
                row = table["coefficients"][g - 1]
                prediction, clamped = row[0], False
                for j, x_j in enumerate(inputs):
                    prediction = prediction + row[j + 1] * x_j
                if position:
                    p = last[position["reading"]]
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

            prediction, clamped = predict(group)
            if group != before and has_previous:
                gap = previous - prediction
            if blend > 0:
                prediction = prediction + float(blend) / float(blend_samples + 1) * gap
            previous, has_previous = prediction, True
            target = -prediction
            if dead:
                ref = last[dead["reading"]]
                if any(abs(last[m] - ref) > dead["threshold_c"] for m in range(dead["n_measured"])):
                    band_target = target
                else:
                    target = band_target
            if checks:
                correction = checks.correct(prediction, held)
                prediction, target = prediction + correction, target - correction

        if faulted:
            has_previous = False
        if blend > 0:
            blend -= 1

        # clamp, rate limit, output
        target = max(min(target, table["comp_max_um"]), table["comp_min_um"])
        delta = max(min(target - comp, table["rate_limit_um"]), -table["rate_limit_um"])
        comp = comp + delta
        fault = held * bits["held"] + faulted * bits["sensor"]
        if clamped:
            fault += bits["position"]
        out.append((table["sensor_fault_return"] if faulted else group, fault, prediction, comp))
        if checks and not math.isnan(probes[i]):
            probe_codes.append(checks.probe(float(probes[i])))
    return out


def compensation(table: dict, readings: np.ndarray) -> np.ndarray:
    """The compensation (um) per sample of :func:`run_table`."""
    return np.array([comp for *_, comp in run_table(table, readings)])
