"""What a valid switching section of a model file is, and the derived inputs it may switch on.

:func:`rule_section_problem` checks the ``switching`` section (the criterion,
the windows, thresholds and directions recomputed from the breaks, the
limits); :func:`parse_derived` reads the ``derived_inputs`` entries.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from groupfit.controller_limits import MAX_HOLD_SAMPLES as HOLD
from groupfit.errors import InputError
from groupfit.features import STARTS, Feature
from groupfit.training_checks import is_number as _is_number

SOURCE_RANGES_KEY = "source_ranges"
"""Key of the switching section holding the valid range of every other column of the modelling run."""
MAX_DELAY_SAMPLES = 32767
"""Longest delay line of a derived input (its position is a PLC INT)."""

MAX_MARGIN_C = 50.0
"""Largest criterion noise or margin (°C) a model file may hold: a wider margin would ignore the criterion."""

RULE_LIMIT = 1.0e9
"""Largest magnitude of a number of the switching rule (thresholds, valid ranges, clamp and rate limit).

The same bound as any reading's valid range (:data:`groupfit.runtime.LEGACY_SOURCE_RANGE`):
exact enough and far inside single precision, which the exported routines may compute in.
"""


DIRECTION_TIE = 1e-9
"""Relative closeness of a criterion's change to the margin that counts as the margin: a change of 3 × 0.05 °C
computed from readings in °C or °F must give the same direction."""


def at_margin(change: float, margin: float) -> bool:
    """Whether a criterion's change is the margin itself, to :data:`DIRECTION_TIE`."""
    return math.isclose(abs(change), margin, rel_tol=DIRECTION_TIE, abs_tol=1e-12)


def switch_direction(change: float, margin: float) -> int:
    """A switching window's direction: 0 when the criterion's change over it is within the margin (a tie,
    :func:`at_margin`, included), else its sign."""
    if abs(change) <= margin or at_margin(change, margin):
        return 0
    return 1 if change > 0 else -1


def is_whole(value) -> bool:
    """An int that is not a bool."""
    return isinstance(value, int) and not isinstance(value, bool)


def rule_section_problem(model: Mapping[str, Any]) -> str | None:
    """What is wrong with a model file's switching section, or None.

    Only keys that are present are checked, so older files without the rule
    keys stay loadable (the rule then derives them from ``criterion_series``).
    The checks run in a fixed order and the first problem found is the one told.
    """
    section = model.get("switching")
    if not isinstance(section, Mapping):
        return "'switching' must be an object"
    for check in (_criterion_problem, _shape_problem, _value_problem, _source_ranges_problem, _derived_problem):
        problem = check(model, section)
        if problem is not None:
            return problem
    return _switching_agrees(model, section)


def _criterion_problem(model: Mapping[str, Any], section: Mapping[str, Any]) -> str | None:
    n_temps = len(model.get("temps", []))
    index = section.get("criterion_index", 0)
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < n_temps:
        return f"switching.criterion_index must be a column number 0…{n_temps - 1}"
    series = section.get("criterion_series", [0.0])
    if not isinstance(series, list) or not series or not all(_is_number(v) for v in series):
        return "switching.criterion_series must be a list of finite numbers"
    return None


def _shape_problem(model: Mapping[str, Any], section: Mapping[str, Any]) -> str | None:
    """The lists' lengths and entries, the bumpless transfer's length and the rule's version."""
    n_temps, n_breaks = len(model.get("temps", [])), len(model.get("breaks", []))
    per_break = {"windows": n_breaks, "thresholds_c": n_breaks, "directions": n_breaks}
    per_sensor = {"temp_min_c": n_temps, "temp_max_c": n_temps}
    for key, length in {**per_break, **per_sensor}.items():
        if key in section and (not isinstance(section[key], list) or len(section[key]) != length):
            return f"switching.{key} must be a list of {length} entries"
    for key in ("thresholds_c", "temp_min_c", "temp_max_c"):
        if key in section and not all(_is_number(v) for v in section[key]):
            return f"switching.{key} must hold finite numbers"
    if "directions" in section and not all(is_whole(v) and v in (-1, 0, 1) for v in section["directions"]):
        return "switching.directions must hold -1, 0 or 1"
    if "windows" in section and not all(_is_window(w) for w in section["windows"]):
        return "switching.windows must be [first, last] sample pairs with 1 ≤ first ≤ last"
    blend = section.get("blend_samples", 0)  # the bumpless transfer's length in samples (a PLC INT holds it)
    if not (is_whole(blend) and 0 <= blend <= 10_000):
        return "switching.blend_samples must be a whole number 0…10000"
    if "rule" in section and section["rule"] != "groupfit-switch/1":
        return f"switching.rule = {section['rule']!r}: this version knows 'groupfit-switch/1'"
    return None


def _is_window(window: Any) -> bool:
    return (
        isinstance(window, list)
        and len(window) == 2
        and all(is_whole(v) for v in window)
        and 1 <= window[0] <= window[1]
    )


def _value_problem(model: Mapping[str, Any], section: Mapping[str, Any]) -> str | None:
    """The numbers' magnitudes and the bounds between them."""
    for key in ("noise_c", "margin_c", "comp_min_um", "comp_max_um", "rate_limit_um", "period_tolerance"):
        if key in section and not _is_number(section[key]):
            return f"switching.{key} must be a finite number"
    for key in ("thresholds_c", "temp_min_c", "temp_max_c", "comp_min_um", "comp_max_um", "rate_limit_um"):
        values = section.get(key)
        values = values if isinstance(values, list) else [values] if values is not None else []
        if any(abs(v) > RULE_LIMIT for v in values):
            return f"switching.{key} exceeds {RULE_LIMIT:g} in magnitude"
    for key in ("noise_c", "margin_c"):
        if key in section and not 0 <= section[key] <= MAX_MARGIN_C:
            return f"switching.{key} = {section[key]!r}: must lie between 0 and {MAX_MARGIN_C:g} °C"
    if "rate_limit_um" in section and section["rate_limit_um"] <= 0:
        return "switching.rate_limit_um must be positive"
    if "comp_min_um" in section and "comp_max_um" in section and section["comp_min_um"] >= section["comp_max_um"]:
        return "switching.comp_min_um must be less than comp_max_um (a clamp with no width serves one value)"
    for key, sign, word in (("comp_min_um", 1, "above"), ("comp_max_um", -1, "below")):
        if key in section and sign * section[key] > 0:
            return (
                f"switching.{key} = {section[key]!r}: {word} 0, the clamp never lets the compensation be 0 (a model "
                "that predicts no error would still move the axis); fit writes ±twice the largest prediction"
            )
    if "hold_samples" in section and not (is_whole(section["hold_samples"]) and 0 <= section["hold_samples"] <= HOLD):
        return f"switching.hold_samples must be a whole number in 0…{HOLD} (a controller's 32-bit counter)"
    if "period_tolerance" in section and not 0 < section["period_tolerance"] < 1:
        return "switching.period_tolerance must lie between 0 and 1 (a fraction of the period)"
    if "temp_min_c" in section and "temp_max_c" in section:
        if any(lo > hi for lo, hi in zip(section["temp_min_c"], section["temp_max_c"])):
            return "switching.temp_min_c must not exceed temp_max_c"
    return None


def _source_ranges_problem(model: Mapping[str, Any], section: Mapping[str, Any]) -> str | None:
    if SOURCE_RANGES_KEY not in section:
        return None
    ranges = section[SOURCE_RANGES_KEY]
    if not isinstance(ranges, Mapping):
        return f"switching.{SOURCE_RANGES_KEY} must be an object: column -> [min, max]"
    for column, pair in ranges.items():
        if not (
            isinstance(pair, list)
            and len(pair) == 2
            and all(_is_number(v) and abs(v) <= RULE_LIMIT for v in pair)
            and pair[0] <= pair[1]
        ):
            return f"switching.{SOURCE_RANGES_KEY}['{column}'] must be [min, max] with min <= max"
    return None


def _derived_problem(model: Mapping[str, Any], section: Mapping[str, Any]) -> str | None:
    """The derived inputs: parsed, each one of the model's inputs once, none the switching criterion."""
    try:
        features = parse_derived(model.get("derived_inputs", []))
    except InputError as exc:
        return str(exc)
    temps = model.get("temps", [])
    defined = {f.name for f in features}
    criterion = temps[section.get("criterion_index", 0)]
    if criterion in defined:
        return (
            f"switching.criterion_index names the derived input '{criterion}'; "
            "the switching criterion must be a measured input"
        )
    for k, feature in enumerate(features):
        if feature.name not in temps:
            return f"derived_inputs[{k}] ('{feature.name}') is not one of the model's inputs (temps)"
        if feature.name in [f.name for f in features[:k]]:
            return f"derived_inputs[{k}] ('{feature.name}') is defined twice"
    for name in temps:
        if isinstance(name, str) and name not in defined and _looks_derived(name):
            return f"input '{name}' is named as a derived input, but derived_inputs does not define it"
    return None


def _looks_derived(name: str) -> bool:
    """Whether an input name has the form of a derived input's (``T_amb~lp1800s``, ``(speed/1000)^1.667``)."""
    return "~" in name or (name.startswith("(") and ")^" in name)


def _switching_agrees(model: Mapping[str, Any], section: Mapping[str, Any]) -> str | None:
    """Whether the derived parts of the switching section agree with the breaks (recomputed and compared).

    The windows are what :func:`groupfit.runtime.switch_windows` gives for the
    breaks and n; each threshold is the criterion series at its window's
    first sample; the criterion's name is the input it indexes.
    """
    temps, breaks, n = model.get("temps"), model.get("breaks"), model.get("n")
    if not (isinstance(temps, list) and isinstance(breaks, list) and is_whole(n)):
        return None
    index = section.get("criterion_index", 0)
    criterion = section.get("criterion")
    if criterion is not None and not isinstance(criterion, str):
        return "switching.criterion must be an input name"
    if criterion is not None and criterion != temps[index]:
        return f"switching.criterion '{criterion}' is not input {index} ('{temps[index]}') named by criterion_index"
    windows = [[int(b) - n + 1, max(int(b), int(b) - n + 1)] for b in breaks]
    if "windows" in section and section["windows"] != windows:
        return f"switching.windows {section['windows']} do not match breaks {breaks} and n = {n} ({windows})"
    series = section.get("criterion_series")
    if series is not None:
        if any(first > len(series) for first, _ in windows):
            return f"switching.criterion_series holds {len(series)} samples; the breaks {breaks} need more"
        if "directions" in section and "margin_c" in section:
            for k, (first, last) in enumerate(windows):
                change = float(series[min(last, len(series)) - 1] - series[max(first - 2, 0)])
                expected = switch_direction(change, section["margin_c"])
                tie = at_margin(change, section["margin_c"])  # a file written before ties counted as the margin
                if section["directions"][k] != expected and not tie:
                    return (
                        f"switching.directions[{k}] = {section['directions'][k]!r} does not match the criterion "
                        f"series over window {k + 1} (expected {expected})"
                    )
        if "thresholds_c" in section:
            for k, (first, _) in enumerate(windows):
                expected = float(series[first - 1])
                if not math.isclose(section["thresholds_c"][k], expected, rel_tol=1e-9, abs_tol=1e-9):
                    return (
                        f"switching.thresholds_c[{k}] = {section['thresholds_c'][k]!r} is not the criterion at "
                        f"sample {first} ({expected!r})"
                    )
    return None


def parse_derived(entries: Any) -> list[Feature]:
    """The ``derived_inputs`` entries as Features; InputError for one that does not describe a transform.

    An entry's ``name`` must match its transform, and a delay be at most
    :data:`MAX_DELAY_SAMPLES` samples. A power stage (``exponent`` and
    ``scale``, both finite and > 0) is optional, as is ``start`` (``"steady"``,
    the default, or ``"rest"``): entries written before these keys existed
    load unchanged.
    """
    if not isinstance(entries, list):
        raise InputError("'derived_inputs' must be a list")
    features = []
    for k, entry in enumerate(entries):
        where = f"derived_inputs[{k}]"
        if not isinstance(entry, Mapping) or not isinstance(entry.get("column"), str):
            raise InputError(f"{where} must be an object with a 'column' name")
        tau = entry.get("tau_s")
        if tau is not None and not _is_number(tau):
            raise InputError(f"{where}: tau_s must be a finite number")
        delay = entry.get("delay_samples", 0)
        if not isinstance(delay, int) or isinstance(delay, bool):
            raise InputError(f"{where}: delay_samples must be a whole number")
        for key in ("exponent", "scale"):
            value = entry.get(key)
            if value is not None and not (_is_number(value) and value > 0):
                raise InputError(f"{where}: {key} must be a finite number > 0, not {value!r}")
        if (entry.get("exponent") is None) != (entry.get("scale") is None):
            raise InputError(f"{where}: a power stage needs both 'exponent' and 'scale' (or neither)")
        start = entry.get("start", "steady")
        if start not in STARTS:
            raise InputError(f"{where}: start {start!r} must be one of {', '.join(STARTS)}")
        try:
            feature = Feature.from_dict(entry)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
        if "name" in entry and entry["name"] != feature.name:
            raise InputError(f"{where}: name '{entry['name']}' does not match its transform ('{feature.name}')")
        if feature.transform == "delay" and feature.delay_samples > MAX_DELAY_SAMPLES:
            raise InputError(f"{where}: delay of {feature.delay_samples} samples; at most {MAX_DELAY_SAMPLES}")
        features.append(feature)
    return features
