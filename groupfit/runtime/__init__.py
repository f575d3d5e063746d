"""Run-time coefficient switching: the rule a controller runs, and its reference implementation.

A grouped model holds one coefficient vector per soft group. While a machine
runs, something must pick the vector that serves the current sample. The
paper (docs/methods.md §1, eq. 16) outlines the rule: a sample count that advances
at the modelling run's sampling period, and a criterion temperature compared
with the modelling run's criterion at the same sample index. This package makes
that rule exact; the exported C, Structured Text and JSON routines
(:mod:`groupfit.export`) perform the same operations in the same order, so
their decisions are identical sample for sample.

The rule itself (state, readings and faults, derived inputs, windows and
criterion, prediction, clamp and rate limit) is described once, in
``docs/switching.md``; the JSON export's ``steps`` (:data:`groupfit.export.json_table.STEPS`)
are the same operations written for someone implementing them, and the C and
Structured Text headers say how to call the generated routine.

The package: :mod:`~groupfit.runtime.rule` derives the rule's parameters from
a model and its modelling run, :mod:`~groupfit.runtime.tables` turns a model
into the tables every target embeds, :mod:`~groupfit.runtime.interpreter`
runs them sample by sample (:class:`SwitchingRule`). It depends on the model
file (:mod:`groupfit.model`) only, never on the fitting stack.

Everything is computed in double precision, or, with ``precision="single"``,
in IEEE single precision operation for operation as the C build with
``GF_USE_FLOAT`` (and a PLC's REAL) computes it, so that the results agree bit
for bit. The one exception is the power stage of a derived input,
``(|x| / scale)^exponent`` (the bearing-heat law of a speed): it is computed in
double precision in both modes and every target, with the C library's ``pow``
(:func:`math.pow` in Python, not numpy's power); single precision widens the
float32 value to double and rounds the power to float32 once.
"""

from groupfit.model import MAX_DELAY_SAMPLES, RULE_KEYS, SOURCE_RANGES_KEY
from groupfit.runtime.groups import replay_groups
from groupfit.runtime.interpreter import (
    PROBE_CODE_OFFSET,
    Replay,
    StepResult,
    SwitchingRule,
    check_period,
)
from groupfit.runtime.recalibration import PROBE_APPLIED, PROBE_IGNORED, PROBE_REJECTED, Recalibrator, RecalTable
from groupfit.runtime.rule import (
    COUNT_MAX,
    DERIVATIVE_SCALE_S,
    FAULT_HELD,
    FAULT_NONE,
    FAULT_PERIOD,
    FAULT_POSITION,
    FAULT_SENSOR,
    LEGACY_COMP_LIMIT_UM,
    LEGACY_SOURCE_RANGE,
    LEGACY_TEMP_RANGE_C,
    PERIOD_TOLERANCE,
    RETURN_PERIOD_FAULT,
    RETURN_SENSOR_FAULT,
    RULE_FORMAT,
    SWITCH_CRITERION,
    SWITCH_FORCED,
    SWITCH_NONE,
    RuleSettings,
    complete_rule_section,
    estimate_noise,
    rule_parameters,
    source_ranges,
    source_valid_range,
    switch_windows,
)
from groupfit.runtime.tables import DerivedTable, RuleTables

__all__ = [
    "COUNT_MAX",
    "DERIVATIVE_SCALE_S",
    "FAULT_HELD",
    "FAULT_NONE",
    "FAULT_PERIOD",
    "FAULT_POSITION",
    "FAULT_SENSOR",
    "LEGACY_COMP_LIMIT_UM",
    "LEGACY_SOURCE_RANGE",
    "LEGACY_TEMP_RANGE_C",
    "MAX_DELAY_SAMPLES",
    "PERIOD_TOLERANCE",
    "PROBE_APPLIED",
    "PROBE_CODE_OFFSET",
    "PROBE_IGNORED",
    "PROBE_REJECTED",
    "RETURN_PERIOD_FAULT",
    "RETURN_SENSOR_FAULT",
    "RULE_FORMAT",
    "RULE_KEYS",
    "SOURCE_RANGES_KEY",
    "SWITCH_CRITERION",
    "SWITCH_FORCED",
    "SWITCH_NONE",
    "DerivedTable",
    "RecalTable",
    "Recalibrator",
    "Replay",
    "RuleSettings",
    "RuleTables",
    "StepResult",
    "SwitchingRule",
    "check_period",
    "complete_rule_section",
    "estimate_noise",
    "replay_groups",
    "rule_parameters",
    "source_ranges",
    "source_valid_range",
    "switch_windows",
]
