"""What a valid model file is: every invariant the run-time rule relies on, checked on the file's object.

:func:`model_problem` is the one validator behind :meth:`groupfit.model.ModelFile.from_dict`
(so behind every verb that reads a model file, every save and every export);
the switching section and the derived inputs are checked by
:mod:`groupfit.switching_checks`. Nothing here imports the fitting stack.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

from groupfit.default_columns import scaled_name
from groupfit.error_scale import factor_problem
from groupfit.error_start import logged_spec
from groupfit.errors import InputError
from groupfit.grouping import MAX_SPACING, hard_groups, soft_groups
from groupfit.model_recalibration import recalibration_problem
from groupfit.model_sections import section_shape_problem
from groupfit.reference import reference_problem
from groupfit.switching_checks import (
    MAX_MARGIN_C,
    RULE_LIMIT,
    is_whole,
    parse_derived,
    rule_section_problem,
)
from groupfit.training_checks import (
    data_notes_problem,
    expectation_problem,
    recordings_problem,
    span_problem,
    stage_problem,
)
from groupfit.training_checks import is_number as _is_number

FORMAT = "groupfit-model/1"
COEFFICIENT_LIMIT = 1.0e12
"""Largest magnitude of a coefficient a model file may hold.

Physical coefficients are µm per °C (or per unit of a derived input) and stay
far below 1e6. The bound keeps every product the run-time rule forms finite in
the controller's arithmetic: a valid reading is at most 1e9 in magnitude
(:data:`groupfit.runtime.LEGACY_SOURCE_RANGE`), so a term is at most 1e21 and a
sum of even thousands of terms stays below 1e25, far from single precision's
3.4e38 (a PLC REAL). A coefficient such as 1e308 would overflow to infinity in
double precision already; anything above 1e12 is a corrupted file, not a model.
"""


def _nonfinite(value: Any, where: str) -> str | None:
    """The place of the first NaN or infinity anywhere in a JSON value, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return where
    if isinstance(value, Mapping):
        for key, item in value.items():
            found = _nonfinite(item, f"{where}.{key}" if where else str(key))
            if found:
                return found
    elif isinstance(value, list):
        for k, item in enumerate(value):
            found = _nonfinite(item, f"{where}[{k}]")
            if found:
                return found
    return None


def model_problem(model: Any, required: Sequence[str]) -> str | None:
    """What is wrong with a model file object, or None (the checks of :meth:`ModelFile.from_dict`).

    Every invariant the run-time rule and the exported routines rely on:
    the keys and their types, breaks strictly increasing within (n, N),
    every hard group over-determined (more samples than coefficients) and
    longer than the soft offset n, hard and soft groups equal to what the
    breaks give, finite coefficients of at most :data:`COEFFICIENT_LIMIT` in
    magnitude, unique input names, every derived input defined once and used,
    rule numbers within :data:`RULE_LIMIT`, no NaN or infinity anywhere, a
    switching section that agrees with the breaks (the criterion's name,
    windows, thresholds and directions recomputed and compared), and the
    optional ``position`` (column not an input, order 1…8, travel low < high,
    one row of coefficients per group and power) and ``dead_band`` (a
    reference column, a threshold in (0, 50] °C) sections, and the optional
    ``ridge_alpha`` (≥ 0, a global model only).
    """
    if not isinstance(model, Mapping) or model.get("format") != FORMAT:
        return f"not a {FORMAT} model file (missing or different 'format')"
    if model.get("kind") == "ar1":
        return "an AR(1) model file (kind 'ar1'): replay and export read it; this needs a grouped model (groupfit fit)"
    missing = [key for key in required if key not in model]
    if missing and "kind" not in model and {"c1", "levels", "c2_um"} <= set(model):
        return 'model file lacks key \'kind\': its c1, levels and c2_um are an AR(1) model\'s; add "kind": "ar1"'
    if missing:
        return f"model file lacks key '{missing[0]}'"
    checks = (
        _scalar_problem,
        _inputs_problem,
        _groups_problem,
        _coefficients_problem,
        _training_problem,
        rule_section_problem,
        _reference_check,
        _error_column_problem,
        position_problem,
        dead_band_problem,
        ridge_problem,
        recalibration_problem,
    )
    for check in checks:
        problem = check(model)
        if problem:
            return problem
    where = _nonfinite(dict(model), "")
    if where:
        return f"{where} is not a finite number (NaN and infinities have no place in a model file)"
    return None


def _scalar_problem(model: Mapping[str, Any]) -> str | None:
    period = model["sampling_period_s"]
    if not _is_number(period) or not 0 < period <= RULE_LIMIT:
        return f"sampling_period_s = {period!r}: must be a number of seconds > 0 (at most {RULE_LIMIT:g})"
    if model["objective"] not in ("sae", "sse"):
        return f"objective = {model['objective']!r}: must be 'sae' or 'sse'"
    if not isinstance(model["intercept"], bool):
        return f"intercept = {model['intercept']!r}: must be true or false"
    if model["error"] is not None and not isinstance(model["error"], str):
        return f"error = {model['error']!r}: must be a column name or null"
    if factor_problem(model["error"]):
        return factor_problem(model["error"])
    if not is_whole(model["p"]) or model["p"] < 0:
        return f"p = {model['p']!r}: must be a whole number ≥ 0"
    if not is_whole(model["n"]) or model["n"] < 0:
        return f"n = {model['n']!r}: must be a whole number ≥ 0"
    if not _is_number(model["c"]) or not 0 <= model["c"] <= MAX_SPACING:
        return f"c = {model['c']!r}: must be a number from 0 to {MAX_SPACING:g}"
    if not _is_number(model["objective_value"]) or model["objective_value"] < 0:
        return f"objective_value = {model['objective_value']!r}: must be a finite number ≥ 0"
    n_samples = model.get("n_samples")
    if n_samples is not None and (not is_whole(n_samples) or n_samples < 1):
        return f"n_samples = {n_samples!r}: must be a whole number ≥ 1"
    return None


def _training_problem(model: Mapping[str, Any]) -> str | None:
    training = model.get("training")
    if training is not None and not isinstance(training, Mapping):
        return "'training' must be an object"
    return (
        expectation_problem(training or {})
        or recordings_problem(training or {})
        or data_notes_problem(training or {})
        or span_problem(training or {})
        or stage_problem(training or {}, model["temps"], len(model["coefficients"]))
    )


def _inputs_problem(model: Mapping[str, Any]) -> str | None:
    temps = model["temps"]
    if not isinstance(temps, list) or not temps:
        return "'temps' must be a non-empty list of input names"
    for k, name in enumerate(temps):
        if not isinstance(name, str) or not name.strip():
            return f"temps[{k}] = {name!r}: input names must be non-empty strings"
        if name in temps[:k]:
            return f"temps: input '{name}' is listed twice (positions {temps.index(name) + 1} and {k + 1})"
    return None


def _groups_problem(model: Mapping[str, Any]) -> str | None:
    p, n, breaks = model["p"], model["n"], model["breaks"]
    if not isinstance(breaks, list) or not all(is_whole(b) for b in breaks):
        return "'breaks' must be a list of whole sample numbers"
    if len(breaks) != p:
        return f"'breaks' holds {len(breaks)} break(s) but p = {p}"
    soft = model["soft_groups"]
    if not isinstance(soft, list) or not all(
        isinstance(g, list) and len(g) == 2 and all(is_whole(v) for v in g) for g in soft
    ):
        return "'soft_groups' must be a list of [first, last] sample pairs"
    if len(soft) != p + 1:
        return f"'soft_groups' holds {len(soft)} group(s) but p = {p} breaks make {p + 1}"
    n_samples = model.get("n_samples")
    if n_samples is None:
        n_samples = soft[-1][1]
    if not is_whole(n_samples) or n_samples < 1:
        return f"the last soft group ends at sample {n_samples!r}; it must be ≥ 1"
    if any(b2 <= b1 for b1, b2 in zip(breaks, breaks[1:])):
        return f"breaks {breaks} must be strictly increasing"
    if breaks and not (n < breaks[0] and breaks[-1] < n_samples):
        return f"breaks {breaks} must lie strictly between n = {n} and N = {n_samples}"
    n_coef = len(model["temps"]) + int(model["intercept"]) if isinstance(model["temps"], list) else 0
    hard = hard_groups(breaks, n_samples)
    for j, (first, last) in enumerate(hard, start=1):
        size = last - first + 1
        if size <= n_coef:
            return (
                f"hard group {j} (samples {first}…{last}) holds {size} sample(s); every group needs more "
                f"than its M = {n_coef} coefficients"
            )
        if j <= p and size <= n:
            return (
                f"hard group {j} (samples {first}…{last}) holds {size} sample(s); "
                f"the soft offset n = {n} must be smaller"
            )
    stored_hard = model.get("hard_groups")
    if stored_hard is not None and stored_hard != [list(g) for g in hard]:
        return f"'hard_groups' {stored_hard} do not match breaks {breaks} and N = {n_samples}"
    expected_soft = [list(g) for g in soft_groups(breaks, n_samples, n)]
    if soft != expected_soft:
        return f"'soft_groups' {soft} do not match breaks {breaks}, n = {n} and N = {n_samples} ({expected_soft})"
    group_objective = model.get("group_objective")
    if group_objective is not None and (
        not isinstance(group_objective, list)
        or len(group_objective) != p + 1
        or not all(_is_number(v) for v in group_objective)
    ):
        return f"'group_objective' must be a list of {p + 1} finite numbers"
    return None


def _coefficients_problem(model: Mapping[str, Any]) -> str | None:
    coefficients = model["coefficients"]
    n_groups = model["p"] + 1
    if not isinstance(coefficients, list) or len(coefficients) != n_groups:
        return f"'breaks' and 'coefficients' do not match p = {model['p']} (one coefficient list per group)"
    width = len(model["temps"]) + int(model["intercept"])
    for g, row in enumerate(coefficients, start=1):
        if not isinstance(row, list) or len(row) != width or not all(_is_number(v) for v in row):
            return f"coefficients of group {g} must be {width} finite numbers"
        largest = max(abs(v) for v in row)
        if largest > COEFFICIENT_LIMIT:
            return (
                f"coefficients of group {g}: {largest:g} exceeds the limit of {COEFFICIENT_LIMIT:g} in magnitude "
                "(a corrupted file; no thermal model has such a coefficient)"
            )
    return None


MAX_POSITION_ORDER = 8
"""Highest polynomial order in the position a model file may hold."""


def position_problem(model: Mapping[str, Any]) -> str | None:
    """What is wrong with the optional ``position`` section, or None."""
    problem = section_shape_problem(model, "position", ("column", "p0_mm", "order", "travel_mm", "coefficients"))
    section = model.get("position")
    if problem or section is None:
        return problem
    column = section["column"]
    if not isinstance(column, str) or not column.strip():
        return "position.column must be a column name"
    if column in model["temps"]:
        return f"position.column '{column}' is also a model input"
    derived = model.get("derived_inputs")
    sources = {e.get("column") for e in derived if isinstance(e, Mapping)} if isinstance(derived, list) else set()
    if column == model.get("reference") or column in sources:
        return f"position.column '{column}' is also the reference or the source of a derived input"
    order = section["order"]
    if not is_whole(order) or not 1 <= order <= MAX_POSITION_ORDER:
        return f"position.order = {order!r}: must be a whole number 1…{MAX_POSITION_ORDER}"
    travel = section["travel_mm"]
    if not (
        isinstance(travel, list)
        and len(travel) == 2
        and all(_is_number(v) and abs(v) <= RULE_LIMIT for v in travel)
        and travel[0] < travel[1]
    ):
        return "position.travel_mm must be [low, high] in mm with low < high"
    p0 = section["p0_mm"]
    if not _is_number(p0) or abs(p0) > RULE_LIMIT:
        return "position.p0_mm must be a finite number of mm"
    ranges = section.get("coefficient_ranges")
    if ranges is not None and not (
        isinstance(ranges, list)
        and len(ranges) == order
        and all(isinstance(r, list) and len(r) == 2 and all(_is_number(v) for v in r) and r[0] <= r[1] for r in ranges)
    ):
        return f"position.coefficient_ranges must hold {order} [min, max] pair(s)"
    width = len(model["temps"]) + int(model["intercept"])
    rows = section["coefficients"]
    if not isinstance(rows, list) or len(rows) != model["p"] + 1:
        return f"position.coefficients must hold one entry per group ({model['p'] + 1})"
    for g, group in enumerate(rows, start=1):
        if not isinstance(group, list) or len(group) != order:
            return f"position.coefficients of group {g} must hold {order} row(s), one per power of (P - P0)"
        for k, row in enumerate(group, start=1):
            if not isinstance(row, list) or len(row) != width or not all(_is_number(v) for v in row):
                return f"position.coefficients of group {g}, power {k}: must be {width} finite numbers"
            if max(abs(v) for v in row) > COEFFICIENT_LIMIT:
                return f"position.coefficients of group {g}, power {k}: exceeds {COEFFICIENT_LIMIT:g} in magnitude"
    return None


def dead_band_problem(model: Mapping[str, Any]) -> str | None:
    """What is wrong with the optional ``dead_band`` section, or None."""
    section = model.get("dead_band")
    if section is None:
        return None
    if not isinstance(section, Mapping) or not isinstance(section.get("reference"), str):
        return "'dead_band' must be an object with a 'reference' column"
    threshold = section.get("threshold_c")
    if not _is_number(threshold) or not 0 < threshold <= MAX_MARGIN_C:
        return f"dead_band.threshold_c = {threshold!r}: must lie in (0, {MAX_MARGIN_C:g}] °C"
    position = model.get("position")
    if isinstance(position, Mapping) and position.get("column") == section["reference"]:
        return "dead_band.reference must be a temperature, not the position column"
    return None


MAX_RIDGE_ALPHA = 1e6
"""The largest ridge penalty a model file may record (:mod:`groupfit.models.ridge`)."""


def ridge_problem(model: Mapping[str, Any]) -> str | None:
    """What is wrong with the optional ``ridge_alpha`` (the penalty the coefficients were fitted with), or None."""
    alpha = model.get("ridge_alpha")
    if alpha is None:
        return None
    if not _is_number(alpha) or not 0 <= alpha <= MAX_RIDGE_ALPHA:
        return f"ridge_alpha = {alpha!r}: must be a number in [0, {MAX_RIDGE_ALPHA:g}]"
    if model.get("p") != 0:
        return f"ridge_alpha with p = {model.get('p')!r}: a ridge penalty belongs to a global model (p = 0)"
    return None


def _reference_check(model: Mapping[str, Any]) -> str | None:
    """The ``reference`` key's problem: it must name no measured input (a derived input of it is fine)."""
    try:
        derived = {feature.name for feature in parse_derived(model.get("derived_inputs", []))}
    except InputError:
        derived = set()
    return reference_problem(model.get("reference"), [name for name in model["temps"] if name not in derived])


def _error_column_problem(model: Mapping[str, Any]) -> str | None:
    """The ``error`` key's problem: its column (less a factor or ``-start``) must be none the rule reads as a
    temperature or position, nor the run's time."""
    error = model["error"]
    if error is None:
        return None
    column = logged_spec(error) or error
    column = (scaled_name(column) or (column, 1.0))[0]
    derived = model.get("derived_inputs") or []
    sources = {d.get("column"): d.get("name") for d in derived if isinstance(d, Mapping)}
    names = {d.get("name") for d in derived if isinstance(d, Mapping)}
    read = {source: f"the source of derived input {name}" for source, name in sources.items()}
    read.update({name: "a model input" for name in model["temps"] if name not in names})
    for key, what in (("reference", "the reference"), ("dead_band", "the dead band's reference")):
        value = model.get(key)
        value = value.get("reference") if isinstance(value, Mapping) else value
        if isinstance(value, str):
            read[value] = what
    position = model.get("position")
    if isinstance(position, Mapping) and isinstance(position.get("column"), str):
        read[position["column"]] = "the axis position"
    training = model.get("training")
    if isinstance(training, Mapping) and isinstance(training.get("time"), str):
        read[training["time"]] = "the run's time"
    if column in read:
        return f"error = {error!r}: column '{column}' is {read[column]}, not the thermal error"
    return None
