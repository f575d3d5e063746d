"""Run-time coefficient switching: the rule a controller runs, and its reference implementation.

A grouped model holds one coefficient vector per soft group. While a machine
runs, something must pick the vector that serves the current sample. The
paper (docs/methods.md §1, eq. 16) outlines the rule: a sample count that advances
at the modelling run's sampling period, and a criterion temperature compared
with the modelling run's criterion at the same sample index. This module makes
that rule exact; the exported C, Structured Text and JSON routines
(:mod:`groupfit.export`) perform the same operations in the same order, so
their decisions are identical sample for sample.

The rule, per sample (``docs/switching.md`` has the full account)
-----------------------------------------------------------------
State: current group ``g`` (1-based, starts at 1), sample count ``i``, the last
good reading of every sensor and how many samples ago it was good, the state
of every derived input (low-pass output, previous value, delay line), and the
compensation value last handed to the controller.

The rule's *readings* (its raw inputs) are the model's measured inputs (the
``temps`` that are not derived), then the source columns of its derived
inputs (``derived_inputs``, :mod:`groupfit.features`) that are not among
them, in order of first appearance in ``temps``.

1. ``i ← i + 1`` (saturating at :data:`COUNT_MAX`).
2. Every reading is *valid* when ``temp_min_c ≤ x ≤ temp_max_c`` (NaN and
   ±inf never are). A valid reading replaces the sensor's last good value; an
   invalid one keeps it and counts a bad sample. Up to ``hold_samples`` (K)
   bad samples in a row are *held* (fault bit 1, the output stays valid);
   more, or a bad reading before any good one, is a *sensor fault*
   (fault bit 2).
   Every derived input is then computed from the last good value of its
   source, with its own state, exactly as :class:`groupfit.features.Feature`
   defines it: ``identity``; ``lowpass`` ``y = b·x + a·y`` (``a = e^{−Δt/τ}``,
   ``b = 1 − a``, the state starts at the source's first good reading);
   ``derivative`` ``(x − x_prev)·3600/Δt`` (0 at the first good reading);
   ``delay`` ``x`` of ``d`` samples before (the first good reading before
   that). A held source feeds its transform as if it were the reading.
3. Switching from group g to g+1 (only while g < G) is possible only inside
   window g, ``first ≤ i ≤ last``: the ``n`` samples that soft groups g and
   g+1 share (the window's first sample is the one from which the offline
   model serves g+1). At ``i ≥ last`` the switch is *forced*; before that it
   happens when the criterion has reached the modelling run's criterion value
   at the window's first sample, ``threshold``, in the direction the
   modelling run was moving: ``criterion − threshold ≥ −margin`` (rising) or
   ``≤ margin`` (falling). A window whose criterion moved less than the
   margin has direction 0 and switches at its first sample, as does any
   window while the criterion sensor is in sensor fault. One group per
   sample at most, never backwards.
4. Prediction ``ŷ = c₀ + Σ c_m·x_m`` of the current group with the model's
   inputs (held readings and derived inputs), accumulated in input order;
   under a sensor fault ``ŷ = 0`` (the safe output: no compensation).
5. Compensation: target ``−ŷ`` (0 under a sensor fault) clamped to
   ``[comp_min_um, comp_max_um]``, then moved from its previous value by at
   most ``rate_limit_um`` per sample. It starts at 0.

The package: :mod:`~groupfit.runtime.rule` derives the rule's parameters from
a model and its modelling run, :mod:`~groupfit.runtime.tables` turns a model
into the tables every target embeds, :mod:`~groupfit.runtime.interpreter`
runs them sample by sample (:class:`SwitchingRule`). It depends on the model
file (:mod:`groupfit.model`) only, never on the fitting stack.

Everything is computed in double precision, or, with ``precision="single"``,
in IEEE single precision operation for operation as the C build with
``GF_USE_FLOAT`` (and a PLC's REAL) computes it, so that the results agree bit
for bit.
"""

from groupfit.model import MAX_DELAY_SAMPLES, RULE_KEYS, SOURCE_RANGES_KEY
from groupfit.runtime.interpreter import Replay, StepResult, SwitchingRule, check_period, replay_groups
from groupfit.runtime.rule import (
    COUNT_MAX,
    DERIVATIVE_SCALE_S,
    FAULT_HELD,
    FAULT_NONE,
    FAULT_PERIOD,
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
    "FAULT_SENSOR",
    "LEGACY_COMP_LIMIT_UM",
    "LEGACY_SOURCE_RANGE",
    "LEGACY_TEMP_RANGE_C",
    "MAX_DELAY_SAMPLES",
    "PERIOD_TOLERANCE",
    "RETURN_PERIOD_FAULT",
    "RETURN_SENSOR_FAULT",
    "RULE_FORMAT",
    "RULE_KEYS",
    "SOURCE_RANGES_KEY",
    "SWITCH_CRITERION",
    "SWITCH_FORCED",
    "SWITCH_NONE",
    "DerivedTable",
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
