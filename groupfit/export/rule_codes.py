"""The run-time rule's codes under the names the C and Structured Text templates give them."""

from __future__ import annotations

from groupfit.runtime import (
    COUNT_MAX,
    FAULT_HELD,
    FAULT_PERIOD,
    FAULT_SENSOR,
    RETURN_PERIOD_FAULT,
    RETURN_SENSOR_FAULT,
    SWITCH_CRITERION,
    SWITCH_FORCED,
)

RULE_CODES = {
    "count_max": COUNT_MAX,
    "fault_held": FAULT_HELD,
    "fault_sensor": FAULT_SENSOR,
    "fault_period": FAULT_PERIOD,
    "ret_sensor": RETURN_SENSOR_FAULT,
    "ret_period": RETURN_PERIOD_FAULT,
    "switch_criterion": SWITCH_CRITERION,
    "switch_forced": SWITCH_FORCED,
}
"""Template fields of the sample counter's ceiling, the fault bits, the return codes and the switch kinds."""
