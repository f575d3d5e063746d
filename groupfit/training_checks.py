"""Checks of a model file's ``training`` section: the expected next-run error, the recordings a fit recorded and
the fast-response stage."""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

from groupfit.error_start import ZERO_KEY
from groupfit.features import Feature
from groupfit.heldout.span import SPAN_KEY


def is_number(value: Any) -> bool:
    """A finite int or float (not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


RECORDINGS_KEY = "recordings"
DATA_NOTES_KEY = "data_notes"
"""The model file's ``training`` key: what loading did to the modelling logs (glitches left out, a resampling)."""
RECORDING_KEYS = ("path", "sha256", "first_time_s", "last_time_s", "period_s")
LAST_READINGS = "last_readings"
"""A recording's optional key: its last row's input temperatures and error, by column (:mod:`groupfit.pickup`)."""
READING_STEPS = "reading_steps"
"""A recording's optional key: per column of ``last_readings``, its typical change from one sample to the next."""
END_STATE = "end_state"
"""A recording's optional key: the run-time rule's state at the file's end, ``{"samples", "double", "single"}``
(:mod:`groupfit.runtime.state`), checked against the rule when it is used."""
PICKUP_LIMIT = "pickup_limit"
"""A recording's optional key: how far a next file's first row may be from ``last_readings`` to pick up there."""
CLOCK_SHIFT = "clock_shift_s"
"""A recording's optional key, beside ``clock_origin_s``, for a file stamped in local wall-clock time without a UTC
offset: the seconds its clock's changes to and from summer time added to its first row's date-time to put it in
the clock of its last row (:attr:`groupfit.data.Run.clock_shift_s`; 0 where the clock did not change)."""


FAST_KEY = "fast_response"
"""The ``training`` key of the fast-response stage (:mod:`groupfit.fast_response`): ``{"tau_s", "columns",
"coefficients", "slopes"}`` (the gains, and the sensors' slopes without the stage: one list, or one list per
group of a grouped model)."""


def stage_features(columns: Sequence[str], tau_s: float, reference: str | None = None) -> list[Feature]:
    """The low-passes of the fast-response stage: one per sensor, time constant ``tau_s``, then the reference
    column's when the model reads its sensors over one."""
    return [
        Feature(column, "lowpass", tau_s=float(tau_s)) for column in (*columns, *([reference] if reference else []))
    ]


def slopes_per_group(slopes: Any) -> bool:
    """Whether a stage's ``slopes`` hold one list per group (a grouped model) rather than one number per column."""
    return isinstance(slopes, (list, tuple)) and bool(slopes) and all(isinstance(r, (list, tuple)) for r in slopes)


def stage_problem(training: Mapping[str, Any], temps: Sequence[str], n_groups: int = 1) -> str | None:
    """What is wrong with ``training.fast_response`` (None: absent or well formed); ``n_groups``: the model's
    coefficient rows."""
    stage = training.get(FAST_KEY)
    if stage is None:
        return None
    where = f"training.{FAST_KEY}"
    if not isinstance(stage, Mapping):
        return f"{where} must be an object with tau_s, columns, coefficients and slopes"
    tau, columns = stage.get("tau_s"), stage.get("columns")
    if not is_number(tau) or tau <= 0:
        return f"{where}.tau_s = {tau!r}: must be a number of seconds > 0"
    if not isinstance(columns, list) or not all(isinstance(c, str) for c in columns) or not columns:
        return f"{where}.columns must be a list of the model's input names"
    slopes = stage.get("slopes")
    grouped = slopes_per_group(slopes)
    if grouped and len(slopes) != n_groups:
        return f"{where}.slopes must hold one list per group ({n_groups}), or one number per column"
    for key, values in [
        ("coefficients", stage.get("coefficients")),
        *(("slopes", row) for row in (slopes if grouped else [slopes])),
    ]:
        if not isinstance(values, (list, tuple)) or len(values) != len(columns):
            return f"{where}.{key} must hold one number per column ({len(columns)})"
        if not all(is_number(v) for v in values):
            return f"{where}.{key} must be finite numbers"
    reference = stage.get("reference")
    if reference is not None and not isinstance(reference, str):
        return f"{where}.reference = {reference!r}: must be the reference column's name"
    names = [f.name for f in stage_features(columns, tau, reference)]
    missing = [name for name in (*columns, *names) if name not in temps]
    if missing:
        return f"{where}: input {missing[0]!r} is not among the model's inputs (temps)"
    return None


def _numbers_problem(entry: Mapping[str, Any], where: str) -> str | None:
    """What is wrong with an entry's optional numbers: its clock's origin and shift and its error's zero."""
    if "clock_origin_s" in entry and not is_number(entry["clock_origin_s"]):
        return f"{where}.clock_origin_s must be the first row's date-time in seconds since 1970"
    shift = entry.get(CLOCK_SHIFT)
    if shift is not None and not (is_number(shift) and "clock_origin_s" in entry and float(shift) % 3600.0 == 0.0):
        return f"{where}.{CLOCK_SHIFT} must be the whole hours (in seconds) a local clock's changes moved its first row"
    if ZERO_KEY in entry and not is_number(entry[ZERO_KEY]):
        return f"{where}.{ZERO_KEY} must be the error's first reading as logged (µm)"
    return None


def recordings_problem(training: Mapping[str, Any]) -> str | None:
    """What is wrong with ``training.recordings`` (None: absent or well formed)."""
    entries = training.get(RECORDINGS_KEY)
    if entries is None:
        return None
    if not isinstance(entries, list):
        return "training.recordings must be a list of the modelling files"
    for k, entry in enumerate(entries):
        where = f"training.recordings[{k}]"
        if not isinstance(entry, Mapping) or any(key not in entry for key in RECORDING_KEYS):
            return f"{where} must hold {', '.join(RECORDING_KEYS)}"
        if not isinstance(entry["path"], str) or not entry["path"]:
            return f"{where}.path must be the file's path"
        relative = entry.get("path_from_model")
        if relative is not None and (not isinstance(relative, str) or not relative):
            return f"{where}.path_from_model must be the file's path from the model file's folder"
        digest = entry["sha256"]
        if not isinstance(digest, str) or len(digest) != 64 or any(c not in "0123456789abcdef" for c in digest):
            return f"{where}.sha256 must be 64 hex digits"
        clock = [entry[key] for key in ("first_time_s", "last_time_s", "period_s")]
        if not all(is_number(v) for v in clock):
            return f"{where}: first_time_s, last_time_s and period_s must be finite numbers"
        if not (clock[0] <= clock[1] and clock[2] > 0):
            return f"{where}: first_time_s <= last_time_s and period_s > 0 are needed"
        numbers = _numbers_problem(entry, where)
        if numbers:
            return numbers
        for key, least in ((LAST_READINGS, -math.inf), (READING_STEPS, 0.0)):
            readings = entry.get(key, {})
            if not isinstance(readings, Mapping) or not all(
                isinstance(column, str) and is_number(value) and value >= least for column, value in readings.items()
            ):
                kind = "numbers" if key == LAST_READINGS else "numbers >= 0"
                return f"{where}.{key} must map each column to {kind}"
        saved = entry.get(END_STATE)
        if saved is not None and not (
            isinstance(saved, Mapping)
            and isinstance(saved.get("samples"), int)
            and saved["samples"] > 0
            and all(isinstance(saved.get(p), Mapping) for p in ("double", "single"))
        ):
            return f"{where}.{END_STATE} must hold samples (a whole number > 0) and the double and single states"
        if PICKUP_LIMIT in entry and not (is_number(entry[PICKUP_LIMIT]) and entry[PICKUP_LIMIT] >= 0):
            return f"{where}.{PICKUP_LIMIT} must be a number >= 0"
    return None


def data_notes_problem(training: Mapping[str, Any]) -> str | None:
    """What is wrong with ``training.data_notes`` (None: absent or a list of lines)."""
    notes = training.get(DATA_NOTES_KEY)
    if notes is None or (isinstance(notes, list) and all(isinstance(n, str) and n for n in notes)):
        return None
    return "training.data_notes must be a list of lines (what loading did to the modelling logs)"


def span_problem(training: Mapping[str, Any]) -> str | None:
    """What is wrong with ``training.input_span`` (None: absent, or ``{input: [lowest, highest]}``)."""
    span = training.get(SPAN_KEY)
    if span is None:
        return None
    if not isinstance(span, Mapping):
        return f"training.{SPAN_KEY} must be an object: each input's [lowest, highest] on the modelling run"
    for name, bounds in span.items():
        if (
            not isinstance(bounds, list)
            or len(bounds) != 2
            or not all(is_number(b) for b in bounds)
            or bounds[0] > bounds[1]
        ):
            return f"training.{SPAN_KEY}.{name} = {bounds!r}: must be [lowest, highest], two numbers"
    return None


def expectation_problem(training: Mapping[str, Any]) -> str | None:
    """The next-run expectation under ``training``: a number ≥ 0, its range [low, high] around it, a method."""
    if "expected_next_run_rms_um" not in training:
        return None
    value = training["expected_next_run_rms_um"]
    if not is_number(value) or value < 0:
        return f"training.expected_next_run_rms_um = {value!r}: must be a finite number ≥ 0"
    bounds = training.get("expected_next_run_range_um")
    if (
        not isinstance(bounds, list)
        or len(bounds) != 2
        or not all(is_number(b) for b in bounds)
        or not bounds[0] <= value <= bounds[1]
    ):
        return f"training.expected_next_run_range_um = {bounds!r}: must be [low, high] with low <= expected <= high"
    if not isinstance(training.get("expected_next_run_method"), str):
        return "training.expected_next_run_method must say how the expectation was estimated"
    return None
