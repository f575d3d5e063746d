"""JSON export: the rule's tables and parameters for any other runtime.

One file, ``groupfit_runtime.json``, holds every number the rule needs and
the step written out in words; a runtime that performs those steps in that
order (double precision) makes the decisions of ``groupfit replay``.
"""

from __future__ import annotations

from groupfit.modelfile import to_json
from groupfit.switching import (
    COUNT_MAX,
    FAULT_HELD,
    FAULT_SENSOR,
    RETURN_SENSOR_FAULT,
    RULE_FORMAT,
    SWITCH_CRITERION,
    SWITCH_FORCED,
    RuleTables,
)

RUNTIME_FORMAT = "groupfit-runtime/1"

STEPS = (
    "count = min(count + 1, count_max); count starts at 0, group at 1, compensation at 0, "
    "and bad[m] at hold_samples + 1 (no good reading yet)",
    "for every sensor m in order: if temp_min_c[m] <= x[m] <= temp_max_c[m] (false for NaN and +-inf) "
    "then last[m] = x[m], bad[m] = 0; else if bad[m] <= hold_samples then bad[m] += 1. "
    "faulted = some bad[m] > hold_samples; held = some 0 < bad[m] <= hold_samples",
    "if group < number of groups, with window w = group (1-based): if count >= windows[w].last then "
    "group += 1 (forced); else if count >= windows[w].first and (bad[criterion] > hold_samples or "
    "directions[w] == 0 or (directions[w] > 0 and last[criterion] - thresholds_c[w] >= -margin_c) or "
    "(directions[w] < 0 and last[criterion] - thresholds_c[w] <= margin_c)) then group += 1",
    "if faulted: prediction = 0, target = 0; else prediction = coefficients[group][0], then for m in order "
    "prediction = prediction + coefficients[group][m + 1] * last[m]; target = -prediction",
    "target = min(max(target, comp_min_um), comp_max_um) (upper bound first, then lower); "
    "delta = target - compensation limited to [-rate_limit_um, rate_limit_um]; compensation += delta",
    "output: group (or the sensor-fault return), prediction (um), compensation (um), "
    "fault = held * fault_bits.held + faulted * fault_bits.sensor",
)


def runtime_table(tables: RuleTables) -> dict:
    """The JSON object of :func:`render_json`."""
    return {
        "format": RUNTIME_FORMAT,
        "rule": RULE_FORMAT,
        "temps": list(tables.temp_names),
        "criterion": tables.criterion,
        "criterion_index": tables.criterion_index,
        "sampling_period_s": tables.sampling_period_s,
        "period_tolerance_s": tables.period_tolerance_s,
        "coefficients": tables.coefficients.tolist(),
        "coefficients_layout": "one row per group: constant (um), then um/degC per temperature in 'temps' order",
        "windows": [[first, last] for first, last in zip(tables.window_first, tables.window_last)],
        "directions": list(tables.directions),
        "thresholds_c": list(tables.thresholds_c),
        "margin_c": tables.margin_c,
        "hold_samples": tables.hold_samples,
        "temp_min_c": list(tables.temp_min_c),
        "temp_max_c": list(tables.temp_max_c),
        "comp_min_um": tables.comp_min_um,
        "comp_max_um": tables.comp_max_um,
        "rate_limit_um": tables.rate_limit_um,
        "count_max": COUNT_MAX,
        "fault_bits": {"held": FAULT_HELD, "sensor": FAULT_SENSOR},
        "sensor_fault_return": RETURN_SENSOR_FAULT,
        "switch_codes": {"criterion": SWITCH_CRITERION, "forced": SWITCH_FORCED},
        "steps": list(STEPS),
    }


def render_json(tables: RuleTables) -> dict[str, str]:
    """``{"groupfit_runtime.json": text}``."""
    return {"groupfit_runtime.json": to_json(runtime_table(tables))}
