"""A model run at another sampling period than the one it was fitted at.

A model without breaks counts nothing: its prediction at a sample uses only
that sample's readings, so it runs at any period (a position model fitted on
check runs every 2 min runs on a 10 s controller stream). What the rule does
count is rescaled to the new period so that it means the same in seconds:

* a low-pass input keeps its time constant: its coefficients ``a = e^{−Δt/τ}``
  are recomputed for the new ``Δt`` (the exact discretisation of the same
  continuous filter, :class:`groupfit.runtime.RuleTables`); a derivative's
  factor ``3600/Δt`` and an on-time's step ``Δt/3600`` likewise;
* a delay line of ``D`` samples becomes ``D·Δt/Δt'`` samples where that is a
  whole number, and is refused otherwise;
* the hold of a faulty reading keeps its length in seconds (at least one
  sample);
* the rate limit per sample grows with a longer period (the same limit per
  second) and is kept with a shorter one (the output is never held back more
  than at the model's own period).

A model with breaks switches groups by sample count (its windows and forced
switches are sample indices of the modelling run) and is refused at another
period: resample the run, or fit at the controller's period.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Mapping

from groupfit.data import MAX_TIME_S
from groupfit.errors import InputError
from groupfit.model import MAX_DELAY_SAMPLES, ModelFile
from groupfit.runtime.rule import complete_rule_section
from groupfit.sampling import MIN_PERIOD_S

WHOLE_TOLERANCE = 1e-9
"""How close a rescaled sample count must be to a whole number to be taken as one."""


def period_differs(model: ModelFile, period_s: float) -> bool:
    """Whether ``period_s`` lies outside the model's period tolerance (NaN and non-positive periods do)."""
    section = complete_rule_section(model)
    tolerance = float(section.period_tolerance) * float(model.sampling_period_s)
    return not abs(float(period_s) - float(model.sampling_period_s)) <= tolerance


def at_period(model: ModelFile | Mapping[str, Any], period_s: float) -> ModelFile:
    """The model as it runs every ``period_s`` seconds (module docstring); itself within its tolerance.

    Raises
    ------
    InputError
        The period is not a positive number, the model has breaks, or a delay
        line does not rescale to a whole number of samples; the line names the
        two periods and what cannot be rescaled.
    """
    model = ModelFile.coerce(model)
    if not period_differs(model, period_s):
        return model
    old = float(model.sampling_period_s)
    head = f"sampling period {period_s:g} s differs from the model's {old:g} s"
    if not (math.isfinite(period_s) and MIN_PERIOD_S <= period_s <= MAX_TIME_S):
        raise InputError(
            f"{head}: a sampling period must be a number of seconds from {MIN_PERIOD_S:g} to {MAX_TIME_S:g}"
        )
    if model.breaks:
        raise InputError(
            f"{head}: the model switches groups by sample count (p = {len(model.breaks)}, breaks at samples "
            f"{', '.join(str(b) for b in model.breaks)}), which is exact only at its own period; "
            + _what_to_do(old, float(period_s))
        )
    ratio = old / float(period_s)
    features, names = [], {}
    for feature in model.derived_inputs or ():
        if feature.transform == "delay":
            samples = feature.delay_samples * ratio
            whole = abs(samples - round(samples)) <= WHOLE_TOLERANCE * max(1.0, samples)
            if not whole or not 1 <= round(samples) <= MAX_DELAY_SAMPLES:
                raise InputError(
                    f"{head}: derived input {feature.name} delays its source by {feature.delay_samples} sample(s) "
                    f"({feature.delay_samples * old:g} s), which is no whole number of {period_s:g} s samples "
                    f"from 1 to {MAX_DELAY_SAMPLES}; " + _what_to_do(old, float(period_s))
                )
            rescaled = dataclasses.replace(feature, delay_samples=int(round(samples)))
            names[feature.name] = rescaled.name
            feature = rescaled
        features.append(feature)
    section = complete_rule_section(model)
    hold = max(1, int(math.floor(int(section.hold_samples) * ratio + WHOLE_TOLERANCE)))
    rate = float(section.rate_limit_um) * max(1.0, 1.0 / ratio)
    switching = section.with_rule({"hold_samples": hold, "rate_limit_um": rate})
    return model.replace(
        sampling_period_s=float(period_s),
        temps=tuple(names.get(name, name) for name in model.temps),
        switching=switching,
        derived_inputs=tuple(features) if model.derived_inputs is not None else None,
    )


def _what_to_do(model_period_s: float, period_s: float) -> str:
    """The advice of a refusal: average the run to the model's period when it is sampled faster, else refit."""
    if period_s < model_period_s:
        return (
            f"average the readings over each {model_period_s:g} s (a run: --resample {model_period_s:g}; on the "
            "controller: export at the model's period and call it every period with the averages), or fit a model "
            "at its own"
        )
    return "fit a model at this period (a run sampled more slowly than the model cannot be resampled to it)"


__all__ = ["at_period", "period_differs"]
