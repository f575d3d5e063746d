"""JSON export: the rule's tables and parameters for any other runtime.

One file, ``groupfit_runtime.json``, holds every number the rule needs and
the step written out in words; a runtime that performs those steps in that
order (double precision) makes the decisions of ``groupfit replay``.

A model with derived inputs is written as ``groupfit-runtime/2``: its
``temps`` (the readings) end with the source columns of the derived inputs,
``inputs`` says what each coefficient multiplies, and ``derived_inputs`` is
the table of transforms. A runtime written for ``groupfit-runtime/1`` (no
derived inputs) refuses it by its format instead of computing with the wrong
inputs.

A model whose derived inputs use a power stage or a start from rest is written
as ``groupfit-runtime/3``: every entry of ``derived_inputs`` also holds
``exponent`` and ``power_scale`` (the power stage ``(|v| / power_scale)^exponent``,
computed in double precision with the C library's ``pow``; both null without
one) and ``start`` (``"steady"`` or ``"rest"``), and the derived-input step of
``steps`` says how they enter. A model with a reference temperature is
written as ``/3`` too, with a ``reference`` object and its step. ``/3`` is one
format: a runtime for it implements both. A runtime written for ``/2``
refuses such a file instead of computing the wrong inputs; models without
them are still written as ``/1`` or ``/2``, byte for byte as before.

A model with an axis position (``position``) or a dead band (``dead_band``) is
written as ``groupfit-runtime/4``, a superset of ``/3``: its ``temps`` end with
the dead band's reference (unless it is already a reading) and the position
(mm); ``position`` holds P0, the travel, the order and the coefficients of
every power of ``P - P0``; ``dead_band`` the reference reading and the
threshold; two more steps say where they enter. Models without them keep
their format, byte for byte.

A model with an on-time derived input (``transform`` ``"ontime"``: the
source's value times the hours it has been non-zero, ``scale`` = Δt/3600) is
written as ``groupfit-runtime/5``, a superset of ``/4`` whose derived-input
step has that branch; a runtime for ``/4`` refuses it. Models without one keep
their format, byte for byte.
"""

from __future__ import annotations

from groupfit.export.json_probe import with_recalibration
from groupfit.export.json_transfer import with_transfer
from groupfit.io import to_json
from groupfit.runtime import (
    COUNT_MAX,
    FAULT_HELD,
    FAULT_POSITION,
    FAULT_SENSOR,
    RETURN_SENSOR_FAULT,
    RULE_FORMAT,
    SWITCH_CRITERION,
    SWITCH_FORCED,
    RuleTables,
)

RUNTIME_FORMAT = "groupfit-runtime/1"
RUNTIME_FORMAT_DERIVED = "groupfit-runtime/2"
RUNTIME_FORMAT_3 = "groupfit-runtime/3"
"""Derived inputs with a power stage or a start from rest, or a reference temperature (either or both):
a runtime for /1 or /2 would compute wrong inputs, so it must refuse the table."""
RUNTIME_FORMAT_4 = "groupfit-runtime/4"
"""A position model or a dead band (a superset of /3)."""
RUNTIME_FORMAT_5 = "groupfit-runtime/5"
"""An on-time derived input (a superset of /4)."""

DERIVED_STEP = (
    "for every derived input k in order, with v = last[derived_inputs[k].reading]: identity: value[k] = v. "
    "Otherwise, if not started[k] and bad[reading] == 0: started[k] = true and memory[k] = v (lowpass, "
    "derivative) or every entry of line[k] (delay_samples long) = v and pos[k] = 0 (delay). Then, if "
    "started[k]: lowpass: memory[k] = b * v + a * memory[k], value[k] = memory[k]; derivative: "
    "value[k] = (v - memory[k]) * scale, memory[k] = v; delay: value[k] = line[k][pos[k]], "
    "line[k][pos[k]] = v, pos[k] += 1, pos[k] = 0 when it reaches delay_samples. started, memory, value, "
    "line and pos start at false / 0"
)
DERIVED_STEP_POWER = (
    "for every derived input k in order, with v = last[derived_inputs[k].reading]; if exponent is not null, "
    "first v = pow(abs(v) / power_scale, exponent), computed in double precision (a single-precision runtime "
    "widens v to double and rounds the result to single once): identity: value[k] = v. "
    "Otherwise, if not started[k] and bad[reading] == 0: started[k] = true and memory[k] = s (lowpass, "
    "derivative) or every entry of line[k] (delay_samples long) = s and pos[k] = 0 (delay), where s = v, "
    "or s = 0 when start is 'rest' (lowpass and delay only). Then, if "
    "started[k]: lowpass: memory[k] = b * v + a * memory[k], value[k] = memory[k]; derivative: "
    "value[k] = (v - memory[k]) * scale, memory[k] = v; delay: value[k] = line[k][pos[k]], "
    "line[k][pos[k]] = v, pos[k] += 1, pos[k] = 0 when it reaches delay_samples. started, memory, value, "
    "line and pos start at false / 0"
)

DERIVED_STEP_ONTIME = DERIVED_STEP_POWER.replace(
    "(lowpass and delay only)", "(lowpass, delay and ontime, whose start is always 'rest')"
).replace(
    "value[k] = (v - memory[k]) * scale, memory[k] = v;",
    "value[k] = (v - memory[k]) * scale, memory[k] = v; ontime: memory[k] = memory[k] + 1 if v != 0, else "
    "memory[k] = 0, then value[k] = v * (memory[k] * scale);",
)

STEPS = (
    "count = min(count + 1, count_max); count starts at 0, group at 1, compensation at 0, "
    "and bad[m] at hold_samples + 1 (no good reading yet)",
    "for every reading m in order: if temp_min_c[m] <= x[m] <= temp_max_c[m] (false for NaN and +-inf) "
    "then last[m] = x[m], bad[m] = 0; else if bad[m] <= hold_samples then bad[m] += 1 (a single-precision "
    "runtime rounds x[m] and the limits to single before the test). "
    "faulted = some bad[m] > hold_samples; held = some 0 < bad[m] <= hold_samples",
    DERIVED_STEP,
    "if group < number of groups, with window w = group (1-based): if count >= windows[w].last then "
    "group += 1 (forced); else if count >= windows[w].first and (bad[criterion] > hold_samples or "
    "directions[w] == 0 or (directions[w] > 0 and last[criterion] - thresholds_c[w] >= -margin_c) or "
    "(directions[w] < 0 and last[criterion] - thresholds_c[w] <= margin_c)) then group += 1",
    "if faulted: prediction = 0, target = 0; else prediction = coefficients[group][0], then for every model "
    "input j in order prediction = prediction + coefficients[group][j + 1] * x[j], where x[j] = "
    "last[inputs[j].reading] or value[inputs[j].derived]; target = -prediction",
    "target = min(max(target, comp_min_um), comp_max_um) (upper bound first, then lower); "
    "delta = target - compensation limited to [-rate_limit_um, rate_limit_um]; compensation += delta",
    "output: group (or the sensor-fault return), prediction (um), compensation (um), "
    "fault = held * fault_bits.held + faulted * fault_bits.sensor",
)
"""The step in words (formats ``/1`` and ``/2``)."""
STEPS_POWER = tuple(DERIVED_STEP_POWER if step is DERIVED_STEP else step for step in STEPS)
"""The step in words of format ``/3``: the derived-input step with the power stage and the start."""


def uses_power_or_rest(tables: RuleTables) -> bool:
    """Whether a derived input has a power stage or starts from rest (format ``/3``)."""
    return any(d.has_power or d.from_rest for d in tables.derived)


def runtime_table(tables: RuleTables) -> dict:
    """The JSON object of :func:`render_json`."""
    inputs = [
        {"name": name, "reading": r} if r >= 0 else {"name": name, "derived": tables.input_derived[j]}
        for j, (name, r) in enumerate(zip(tables.input_names, tables.input_reading))
    ]
    derived = [
        {
            "name": d.name,
            "column": d.column,
            "reading": d.reading,
            "transform": d.transform,
            "tau_s": d.tau_s,
            "a": d.a,
            "b": d.b,
            "scale": d.scale,
            "delay_samples": d.delay_samples,
        }
        for d in tables.derived
    ]
    power = uses_power_or_rest(tables)
    note = (
        "per derived input: its source 'reading' (index into temps); lowpass: "
        "a = exp(-dt/tau_s), b = 1 - a; derivative: scale = 3600/dt (per hour); delay: delay_samples"
    )
    if power:
        for entry, d in zip(derived, tables.derived):
            entry.update(exponent=d.exponent, power_scale=d.power_scale, start=d.start)
        note += (
            "; power stage (null: none): v = (|reading| / power_scale)^exponent in double precision "
            "before the transform; start: 'steady' (state = the first good v) or 'rest' (state = 0)"
        )
    if power:
        fmt = RUNTIME_FORMAT_3
    else:
        fmt = RUNTIME_FORMAT_DERIVED if tables.derived else RUNTIME_FORMAT
    return {
        "format": fmt,
        "rule": RULE_FORMAT,
        "temps": list(tables.raw_names),
        "temps_note": "the readings passed every sample, in this order: the measured model inputs (degC), "
        "then the source columns of the derived inputs (in the unit of their column in the modelling data)",
        "inputs": inputs,
        "derived_inputs": derived,
        "derived_inputs_note": note,
        "criterion": tables.criterion,
        "criterion_index": tables.criterion_reading,
        "sampling_period_s": tables.sampling_period_s,
        "period_tolerance_s": tables.period_tolerance_s,
        "coefficients": tables.coefficients.tolist(),
        "coefficients_layout": "one row per group: constant (um), then one coefficient per entry of 'inputs' "
        "(um per unit of the input)",
        "windows": [[first, last] for first, last in zip(tables.window_first, tables.window_last)],
        "directions": list(tables.directions),
        "thresholds_c": list(tables.thresholds_c),
        "margin_c": tables.margin_c,
        "hold_samples": tables.hold_samples,
        "temp_min_c": list(tables.valid_min),
        "temp_max_c": list(tables.valid_max),
        "comp_min_um": tables.comp_min_um,
        "comp_max_um": tables.comp_max_um,
        "rate_limit_um": tables.rate_limit_um,
        "count_max": COUNT_MAX,
        "fault_bits": {"held": FAULT_HELD, "sensor": FAULT_SENSOR},
        "sensor_fault_return": RETURN_SENSOR_FAULT,
        "switch_codes": {"criterion": SWITCH_CRITERION, "forced": SWITCH_FORCED},
        "steps": list(STEPS_POWER if power else STEPS),
    }


def render_json(tables: RuleTables) -> dict[str, str]:
    """``{"groupfit_runtime.json": text}``."""
    table = with_ontime(with_position(with_reference(runtime_table(tables), tables), tables), tables)
    table = with_transfer(table, tables)
    table = with_recalibration(table, tables)
    return {"groupfit_runtime.json": to_json(table)}


def with_ontime(table: dict, tables: RuleTables) -> dict:
    """The runtime table of a model with an on-time derived input: format /5, the step with its branch."""
    if not any(d.transform == "ontime" for d in tables.derived):
        return table
    steps = [DERIVED_STEP_ONTIME if step == DERIVED_STEP_POWER else step for step in table["steps"]]
    note = table["derived_inputs_note"] + "; ontime: scale = dt/3600 (hours per sample on)"
    return {**table, "format": RUNTIME_FORMAT_5, "steps": steps, "derived_inputs_note": note}


# --------------------------------------------------------------------- reference temperature

REFERENCE_STEP = (
    "reference, after the readings and before the derived inputs: every measured model input m (an entry of "
    "'inputs' with a 'reading') is taken as ref(m) = last[m] - last[reference.reading] (reference.kind "
    "'column'), or ref(m) = last[m] - first[m] (kind 'start': for every measured reading m in order, if not "
    "has_first[m] and bad[m] == 0 then first[m] = last[m], has_first[m] = true; first and has_first start at "
    "0 / false). Every later step that reads last[criterion] or last[inputs[j].reading] uses ref(...) instead; "
    "derived inputs use last[] as read"
)


def with_reference(table: dict, tables: RuleTables) -> dict:
    """The runtime table of a model with a reference temperature: format /3, the reference and its step."""
    if tables.reference is None:
        return table
    steps = list(table["steps"])
    steps.insert(2, REFERENCE_STEP)
    reference = {"kind": "start"} if tables.reference_start else {"kind": "column", "name": tables.reference}
    if tables.reference_reading >= 0:
        reference["reading"] = tables.reference_reading
    return {**table, "format": RUNTIME_FORMAT_3, "reference": reference, "steps": steps}


# --------------------------------------------------------------------- axis position and dead band

POSITION_STEP = (
    "position, after the prediction when not faulted: P = last[position.reading]; if P < travel_mm[0] then "
    "P = travel_mm[0] and clamped = true; if P > travel_mm[1] then P = travel_mm[1] and clamped = true; "
    "d = P - p0_mm; for k = order down to 1: term = coefficients[group][k - 1][0], then for every model input j "
    "in order term = term + coefficients[group][k - 1][j + 1] * x[j]; poly = term for k = order, else "
    "poly = poly * d + term; k0 = prediction, slope = the term of k = 1 (tan beta, um/mm); "
    "prediction = prediction + poly * d. fault += fault_bits.position when clamped"
)
DEAD_BAND_STEP = (
    "dead band, after target = -prediction when not faulted: if some measured reading m (0 <= m < "
    "dead_band.n_measured) has |last[m] - last[dead_band.reading]| > dead_band.threshold_c then band_target = "
    "target, else target = band_target (band_target starts at 0)"
)


def with_position(table: dict, tables: RuleTables) -> dict:
    """The runtime table of a position model or a dead band: format /4, their sections and steps."""
    if not (tables.has_position or tables.has_dead_band):
        return table
    steps = list(table["steps"])
    at = len(steps) - 2  # before the clamp and rate limit
    out = {**table, "format": RUNTIME_FORMAT_4}
    if tables.has_position:
        out["position"] = {
            "name": tables.position_name,
            "reading": tables.position_reading,
            "p0_mm": tables.p0_mm,
            "travel_mm": [tables.travel_min_mm, tables.travel_max_mm],
            "order": tables.position_order,
            "coefficients": tables.position_coefficients.tolist(),
            "coefficients_layout": "per group, per power k = 1..order of (P - P0): constant, then one "
            "coefficient per entry of 'inputs' (um per mm^k)",
        }
        out["fault_bits"] = {**table["fault_bits"], "position": FAULT_POSITION}
        steps.insert(at, POSITION_STEP)
        at += 1
    if tables.has_dead_band:
        out["dead_band"] = {
            "name": tables.raw_names[tables.dead_band_reading],
            "reading": tables.dead_band_reading,
            "threshold_c": tables.dead_band_c,
            "n_measured": tables.n_measured,
        }
        steps.insert(at, DEAD_BAND_STEP)
    out["steps"] = steps
    return out
