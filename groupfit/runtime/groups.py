"""The run-time rule's groups over a whole run of a model's inputs, for offline comparisons."""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.runtime.interpreter import SwitchingRule
from groupfit.runtime.rule import LEGACY_SOURCE_RANGE, complete_rule_section


def replay_groups(model: ModelFile | Mapping[str, Any], inputs) -> np.ndarray:
    """0-based group the run-time rule serves at each row of the model's inputs (double precision).

    For comparisons that score a grouped model on another run through the
    rule a controller would run, rather than by sample index. ``inputs`` is
    the (N, M) matrix of the model's inputs, derived ones included (as
    ModelFile.inputs computes them). The group
    depends only on the sample count and the criterion, a measured input, so
    the rule is replayed on the measured inputs, with every source column
    that is not a model input (and a position or dead-band reading) held at a
    valid value.
    """
    rule = SwitchingRule(without_reference(model))
    t = rule.tables
    inputs = np.asarray(inputs, dtype=float)
    if not t.derived and t.n_temps == t.n_inputs:
        return rule.replay(inputs).group - 1
    if inputs.ndim != 2 or inputs.shape[1] != t.n_inputs:
        raise InputError(f"model inputs of shape {inputs.shape}: the model has {t.n_inputs} inputs")
    readings = np.empty((len(inputs), t.n_temps))
    for j, r in enumerate(t.input_reading):
        if r >= 0:
            readings[:, r] = inputs[:, j]
    for r in range(t.n_measured, t.n_temps):
        readings[:, r] = t.valid_min[r]
    return rule.replay(readings).group - 1


def without_reference(model: ModelFile | Mapping[str, Any]) -> ModelFile:
    """The model taking its inputs already relative to its reference, for :func:`replay_groups`.

    The inputs :meth:`ModelFile.inputs` computes are already rises over the
    reference, so the rule that replays them has no reference and accepts any
    finite value of a measured input (NaN and ±inf stay faults): the valid
    ranges of the model file hold the raw readings, not the rises.
    """
    model = ModelFile.coerce(model)
    if model.reference is None:
        return model
    section = complete_rule_section(model)
    wide = {
        "temp_min_c": [LEGACY_SOURCE_RANGE[0]] * len(model.temps),
        "temp_max_c": [LEGACY_SOURCE_RANGE[1]] * len(model.temps),
    }
    return model.replace(reference=None, switching=section.with_rule(wide))
