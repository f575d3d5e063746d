"""The model file's ``recalibration`` section: how sparse probe checks correct the compensation at run time.

A probe check measures the actual thermal error at one moment (the machine
touches a reference artefact). The section says how the run-time rule folds
those checks into its prediction (the filter itself:
:mod:`groupfit.runtime.recalibration`; how its parameters are chosen:
:mod:`groupfit.recalibration_tuning`; ``docs/recalibration.md``):

``method``
    ``"hold"``: every accepted check's residual becomes the offset, held until
    the next check. ``"kalman"``: a Kalman filter on the offset and the
    ``terms`` it lists besides (``"drift"``: a rate of change of the offset
    that decays with ``drift_tau_h``; ``"gain"``: an error proportional to
    the model's prediction).
noise and start (standard deviations)
    ``offset_sigma_um_per_sqrt_h``, ``drift_sigma_um_per_h_per_sqrt_h``,
    ``gain_sigma_per_sqrt_h`` (how fast each wanders, per √hour),
    ``initial_offset_sigma_um``, ``initial_drift_sigma_um_per_h``,
    ``initial_gain_sigma`` (before the first check), ``probe_sigma_um`` (the
    noise of one check; 0 for the hold).
robustness
    ``gate_sigmas``: a check whose innovation exceeds this many of its
    standard deviations is rejected and flagged, never applied, unless
    ``confirm_after`` checks in a row were rejected before it (a real change,
    not a chip on the artefact). ``significance_sigmas`` (optional, 0 when
    absent): a correction is applied only when the filter's estimate of it
    exceeds this many of its own standard deviations after the last check. ``offset_max_um``, ``drift_max_um_per_h``,
    ``gain_max`` bound the states; ``rate_um_per_sample`` limits how fast the
    applied correction moves.
``chosen``
    How the method and its numbers were chosen (free-form object: the folds,
    check intervals and scores).
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, Mapping

from groupfit.model_sections import section_shape_problem

METHODS = ("hold", "kalman")
TERMS = ("offset", "drift", "gain")
"""States a filter may carry, in the order of its state vector."""
RECALIBRATION_LIMIT = 1.0e6
"""Largest magnitude of a number of the section (µm, hours, σ): far inside single precision."""
MAX_CONFIRM = 1000

NUMBER_KEYS = (
    "offset_sigma_um_per_sqrt_h",
    "drift_sigma_um_per_h_per_sqrt_h",
    "drift_tau_h",
    "gain_sigma_per_sqrt_h",
    "initial_offset_sigma_um",
    "initial_drift_sigma_um_per_h",
    "initial_gain_sigma",
    "probe_sigma_um",
    "gate_sigmas",
    "significance_sigmas",
    "offset_max_um",
    "drift_max_um_per_h",
    "gain_max",
    "rate_um_per_sample",
)
POSITIVE_KEYS = ("offset_sigma_um_per_sqrt_h", "drift_tau_h", "gate_sigmas", "offset_max_um", "rate_um_per_sample")
"""Numbers that must be > 0 (the others ≥ 0): a check's innovation variance is never 0, a drift decays."""
TERM_KEYS = {
    "drift": ("drift_sigma_um_per_h_per_sqrt_h", "initial_drift_sigma_um_per_h"),
    "gain": ("gain_sigma_per_sqrt_h", "initial_gain_sigma"),
}
"""The noise of a term the filter does not carry must be 0 (it stays out of the state)."""


@dataclass(frozen=True, kw_only=True)
class Recalibration:
    """The ``recalibration`` section (keys as in the module docstring)."""

    method: str
    terms: tuple[str, ...] = ("offset",)
    offset_sigma_um_per_sqrt_h: float
    drift_sigma_um_per_h_per_sqrt_h: float = 0.0
    drift_tau_h: float = 1.0
    gain_sigma_per_sqrt_h: float = 0.0
    initial_offset_sigma_um: float
    initial_drift_sigma_um_per_h: float = 0.0
    initial_gain_sigma: float = 0.0
    probe_sigma_um: float = 0.0
    gate_sigmas: float
    significance_sigmas: float = 0.0
    confirm_after: int
    offset_max_um: float
    drift_max_um_per_h: float = 0.0
    gain_max: float = 0.0
    rate_um_per_sample: float
    chosen: Mapping[str, Any] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @property
    def description(self) -> str:
        """One line: the method and its terms."""
        if self.method == "hold":
            return "offset hold"
        return "Kalman filter on " + " + ".join(self.terms)


OPTIONAL_DEFAULTS = {
    f.name: f.default
    for f in fields(Recalibration)
    if f.name in NUMBER_KEYS and f.default is not MISSING  # the keys a section may leave out
}


REQUIRED_KEYS = (
    "method",
    "offset_sigma_um_per_sqrt_h",
    "initial_offset_sigma_um",
    "gate_sigmas",
    "confirm_after",
    "offset_max_um",
    "rate_um_per_sample",
)
"""The keys every ``recalibration`` section holds, in the order a missing one is named."""


def recalibration_problem(model: Mapping[str, Any]) -> str | None:
    """What is wrong with the optional ``recalibration`` section, or None."""
    problem = section_shape_problem(model, "recalibration", REQUIRED_KEYS)
    section = model.get("recalibration")
    if problem or section is None:
        return problem
    method = section["method"]
    if method not in METHODS:
        return f"recalibration.method = {method!r}: must be one of {', '.join(METHODS)}"
    terms = section.get("terms", ["offset"])
    return _terms_problem(method, terms) or _numbers_problem(section, method, terms) or _rest_problem(section)


def _terms_problem(method: str, terms: Any) -> str | None:
    if not isinstance(terms, list) or not terms or terms[0] != "offset" or any(t not in TERMS for t in terms):
        return f"recalibration.terms = {terms!r}: must be 'offset' first, then any of 'drift', 'gain'"
    if len(set(terms)) != len(terms) or terms != [t for t in TERMS if t in terms]:
        return f"recalibration.terms = {terms!r}: each term once, in the order {', '.join(TERMS)}"
    if method == "hold" and terms != ["offset"]:
        return "recalibration: the hold carries the offset only (terms = ['offset']); use method 'kalman'"
    return None


def _numbers_problem(section: Mapping[str, Any], method: str, terms: list) -> str | None:
    for key in NUMBER_KEYS:
        value = section.get(key, OPTIONAL_DEFAULTS.get(key))
        if not _is_number(value) or abs(value) > RECALIBRATION_LIMIT:
            return f"recalibration.{key} = {value!r}: must be a finite number of at most {RECALIBRATION_LIMIT:g}"
        if value < 0 or (key in POSITIVE_KEYS and value == 0):
            return f"recalibration.{key} = {value!r}: must be {'> 0' if key in POSITIVE_KEYS else '≥ 0'}"
    for term, keys in TERM_KEYS.items():
        if term not in terms and any(section.get(key, 0.0) != 0 for key in keys):
            return f"recalibration: '{term}' is not among the terms, so {' and '.join(keys)} must be 0"
    if method == "hold" and section.get("probe_sigma_um", 0.0) != 0:
        return "recalibration.probe_sigma_um must be 0 for the hold (it takes each accepted check as it is)"
    for term, key in (("drift", "drift_max_um_per_h"), ("gain", "gain_max")):
        if term in terms and not section.get(key, 0.0) > 0:
            return f"recalibration.{key} must be > 0 when '{term}' is among the terms"
    return None


def _rest_problem(section: Mapping[str, Any]) -> str | None:
    confirm = section["confirm_after"]
    if not isinstance(confirm, int) or isinstance(confirm, bool) or not 0 <= confirm <= MAX_CONFIRM:
        return f"recalibration.confirm_after = {confirm!r}: must be a whole number 0…{MAX_CONFIRM}"
    chosen = section.get("chosen")
    if chosen is not None and not isinstance(chosen, Mapping):
        return "recalibration.chosen must be an object"
    return None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


__all__ = ["METHODS", "NUMBER_KEYS", "RECALIBRATION_LIMIT", "TERMS", "Recalibration", "recalibration_problem"]
