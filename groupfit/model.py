"""The model file (JSON, ``"format": "groupfit-model/1"``) as one typed, frozen object.

:class:`ModelFile` is what ``groupfit fit`` and ``groupfit diagnose`` write
and what ``replay``, ``export``, ``compare`` and ``diagnose`` read. It owns the
file's keys, their validation, reading and writing, and the offline
prediction of a grouped model (each row served by its group, by sample index
or by groups a caller chose). It imports neither scikit-learn nor DEAP:
:meth:`groupfit.models.grouped.GroupedRegressor.to_model_file` and
:meth:`~groupfit.models.grouped.GroupedRegressor.from_model_file` bridge to
the estimator.

To add an optional key, add a field with a default of ``None`` to
:class:`ModelFile` (or :class:`Switching`) in the place its key should stand in
the file: :meth:`ModelFile.to_dict` writes every field that is not None, in
field order, and :meth:`ModelFile.from_dict` reads it when present, so older
files keep loading. Keys this version does not know are kept (``extra``) and
written back unchanged.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from groupfit.errors import InputError
from groupfit.features import STARTS, Feature, derived_matrix
from groupfit.grouping import serving_group_index
from groupfit.io import atomic_write_text, to_json
from groupfit.reference import reference_problem, referenced

FORMAT = "groupfit-model/1"
SOURCE_RANGES_KEY = "source_ranges"
"""Key of the switching section holding the valid range of every other column of the modelling run."""
MAX_DELAY_SAMPLES = 32767
"""Longest delay line of a derived input (its position is a PLC INT)."""
RULE_KEYS = (
    "rule",
    "windows",
    "thresholds_c",
    "directions",
    "noise_c",
    "margin_c",
    "hold_samples",
    "temp_min_c",
    "temp_max_c",
    "comp_min_um",
    "comp_max_um",
    "rate_limit_um",
    "period_tolerance",
)
"""Keys :func:`groupfit.runtime.rule_parameters` adds to a model file's ``switching`` section."""


def grouped_prediction(
    intercepts: np.ndarray, slopes: np.ndarray, inputs: np.ndarray, groups: np.ndarray
) -> np.ndarray:
    """``intercept[g] + x·slope[g]`` of every row, ``g`` the row's 0-based group: the one grouped prediction."""
    inputs = np.asarray(inputs, dtype=float)
    return intercepts[groups] + np.einsum("ij,ij->i", inputs, slopes[groups])


@dataclass(frozen=True, kw_only=True)
class Switching:
    """The ``switching`` section: the criterion of the run-time rule and, when derived, its parameters.

    Older files may hold only the criterion and its series; the rule then
    derives the rest (:func:`groupfit.runtime.complete_rule_section`).
    ``windows`` … ``period_tolerance`` are the keys of :data:`RULE_KEYS`
    (documented at :func:`groupfit.runtime.rule_parameters`).
    """

    criterion: str | None = None
    criterion_index: int | None = None
    criterion_series: tuple[float, ...] | None = None
    rule: str | None = None
    windows: tuple[tuple[int, int], ...] | None = None
    thresholds_c: tuple[float, ...] | None = None
    directions: tuple[int, ...] | None = None
    noise_c: float | None = None
    margin_c: float | None = None
    hold_samples: int | None = None
    temp_min_c: tuple[float, ...] | None = None
    temp_max_c: tuple[float, ...] | None = None
    comp_min_um: float | None = None
    comp_max_um: float | None = None
    rate_limit_um: float | None = None
    period_tolerance: float | None = None
    source_ranges: Mapping[str, tuple[float, float]] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @property
    def has_rule(self) -> bool:
        """Whether every rule parameter is present."""
        return all(getattr(self, key) is not None for key in RULE_KEYS)

    def with_rule(self, parameters: Mapping[str, Any]) -> "Switching":
        """This section with the rule parameters of :func:`groupfit.runtime.rule_parameters` (keys of RULE_KEYS)."""
        return dataclasses.replace(self, **{key: _frozen(value) for key, value in parameters.items()})

    def to_dict(self) -> dict[str, Any]:
        return _fields_to_dict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Switching":
        return _fields_from_dict(cls, data)


@dataclass(frozen=True, kw_only=True)
class ModelFile:
    """A grouped model as the model file holds it (``groupfit-model/1``).

    Field names are the file's keys (SPEC.md). ``temps`` keeps its file name
    for compatibility: it lists the model's *inputs*, in coefficient order,
    derived inputs included. ``coefficients`` holds one row per soft group,
    the constant first when ``intercept``.
    """

    format: str = FORMAT
    sampling_period_s: float
    temps: tuple[str, ...]
    reference: str | None = None
    error: str | None
    intercept: bool
    objective: str
    p: int
    n: int
    c: float
    n_samples: int | None = None
    breaks: tuple[int, ...]
    hard_groups: tuple[tuple[int, int], ...] | None = None
    soft_groups: tuple[tuple[int, int], ...]
    coefficients: tuple[tuple[float, ...], ...]
    objective_value: float
    group_objective: tuple[float, ...] | None = None
    switching: Switching
    training: Mapping[str, Any] | None = None
    derived_inputs: tuple[Feature, ...] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    # ----------------------------------------------------------------- reading and writing

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | Path | None = None) -> "ModelFile":
        """Check a model file object and build the model; InputError names what is wrong (and ``source``)."""
        prefix = f"{source}: " if source is not None else ""
        problem = model_problem(data)
        if problem:
            raise InputError(prefix + problem)
        nested = {"switching": Switching.from_dict, "derived_inputs": lambda v: tuple(_parse_derived(v))}
        return _fields_from_dict(cls, data, nested)

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of the file: every present key, in the file's order, plain lists and numbers."""
        return _fields_to_dict(self)

    @classmethod
    def load(cls, path: str | Path) -> "ModelFile":
        """Read and check a model file."""
        path = Path(path)
        if not path.is_file():
            raise InputError(f"{path}: model file not found")
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"{path}: not a JSON model file ({exc})") from None
        return cls.from_dict(data, source=path)

    def save(self, path: str | Path) -> None:
        atomic_write_text(path, to_json(self.to_dict()))

    @classmethod
    def coerce(cls, model: "ModelFile | Mapping[str, Any]") -> "ModelFile":
        """A ModelFile from a ModelFile or a model file object (checked)."""
        return model if isinstance(model, ModelFile) else cls.from_dict(model)

    def replace(self, **changes) -> "ModelFile":
        return dataclasses.replace(self, **changes)

    # ----------------------------------------------------------------- what the model holds

    @property
    def n_groups(self) -> int:
        return len(self.coefficients)

    @property
    def n_samples_fit(self) -> int:
        """Samples of the modelling run (older files: the end of the last soft group)."""
        return int(self.n_samples if self.n_samples is not None else self.soft_groups[-1][1])

    @property
    def derived(self) -> dict[str, Feature]:
        """The derived inputs the model uses, by input name, in input order."""
        features = {feature.name: feature for feature in self.derived_inputs or ()}
        return {name: features[name] for name in self.temps if name in features}

    @property
    def measured_inputs(self) -> list[str]:
        """Inputs read from a column as they are (not derived)."""
        derived = self.derived
        return [name for name in self.temps if name not in derived]

    def coefficient_matrix(self) -> np.ndarray:
        """Coefficients as a (G, M+1) array, constant first (0 when the model has none)."""
        coefficients = np.asarray(self.coefficients, dtype=float).reshape(self.n_groups, -1)
        if not self.intercept:
            coefficients = np.column_stack([np.zeros(len(coefficients)), coefficients])
        return coefficients

    @property
    def intercepts(self) -> np.ndarray:
        return self.coefficient_matrix()[:, 0]

    @property
    def slopes(self) -> np.ndarray:
        """(G, M) input coefficients of every group."""
        return self.coefficient_matrix()[:, 1:]

    # ----------------------------------------------------------------- offline prediction

    def serving_groups(self, n_rows: int | None = None) -> np.ndarray:
        """0-based group serving each sample offline, by sample index (rows past the run: the last group)."""
        return serving_group_index(list(self.breaks), self.n_samples_fit, self.n, n_rows)

    def predict(self, inputs, groups: np.ndarray | None = None) -> np.ndarray:
        """Predicted error of every row of the (N, M) input matrix.

        Each row is served by ``groups`` (0-based, e.g. from the run-time rule)
        or, by default, by the group that serves its sample index offline.
        """
        inputs = np.asarray(inputs, dtype=float)
        if inputs.ndim != 2 or inputs.shape[1] != len(self.temps):
            raise InputError(f"inputs of shape {inputs.shape}: the model has {len(self.temps)} inputs")
        if groups is None:
            groups = self.serving_groups(len(inputs))
        matrix = self.coefficient_matrix()
        return grouped_prediction(matrix[:, 0], matrix[:, 1:], inputs, groups)

    def inputs(self, frame, source: str = "the run") -> np.ndarray:
        """The model's input matrix from a table (DataFrame-like): measured columns and derived inputs.

        Derived inputs use the model's sampling period, as the run-time rule
        does (a run's own period may differ from it by up to 1 %).
        """
        derived = self.derived
        columns = []
        for name in self.temps:
            if name in derived:
                columns.append(derived_matrix([derived[name]], frame, self.sampling_period_s)[:, 0])
            elif name in frame.columns:
                columns.append(frame[name].to_numpy(dtype=float))
            else:
                raise InputError(f"{source}: column '{name}' that the model uses is missing")
        return self._apply_reference(np.column_stack(columns), frame, source)

    def _apply_reference(self, inputs: np.ndarray, frame, source: str) -> np.ndarray:
        """The measured inputs relative to the model's reference (:mod:`groupfit.reference`); derived as they are."""
        if self.reference is None:
            return inputs
        derived = self.derived
        measured = [j for j, name in enumerate(self.temps) if name not in derived]
        inputs = inputs.copy()
        inputs[:, measured] = referenced(inputs[:, measured], self.reference, frame, source)
        return inputs


# --------------------------------------------------------------------- validation of the file object

REQUIRED = ("format",) + tuple(
    f.name for f in dataclasses.fields(ModelFile) if f.default is dataclasses.MISSING and f.name != "extra"
)
"""Keys every model file holds: ``format`` and the fields without a default."""


def model_problem(model: Any) -> str | None:
    """What is wrong with a model file object, or None (the checks of :meth:`ModelFile.from_dict`)."""
    if not isinstance(model, Mapping) or model.get("format") != FORMAT:
        return f"not a {FORMAT} model file (missing or different 'format')"
    missing = [key for key in REQUIRED if key not in model]
    if missing:
        return f"model file lacks key '{missing[0]}'"
    n_groups = model["p"] + 1
    if len(model["breaks"]) != model["p"] or len(model["coefficients"]) != n_groups:
        return f"'breaks' and 'coefficients' do not match p = {model['p']}"
    problem = rule_section_problem(model) or _reference_check(model)
    if problem:
        return problem
    width = len(model["temps"]) + int(model["intercept"])
    for g, row in enumerate(model["coefficients"], start=1):
        if len(row) != width or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in row):
            return f"coefficients of group {g} must be {width} finite numbers"
    return None


def rule_section_problem(model: Mapping[str, Any]) -> str | None:
    """What is wrong with a model file's switching section, or None.

    Only keys that are present are checked, so older files without the rule
    keys stay loadable (the rule then derives them from ``criterion_series``).
    """
    section = model.get("switching")
    if not isinstance(section, Mapping):
        return "'switching' must be an object"
    n_temps = len(model.get("temps", []))
    n_breaks = len(model.get("breaks", []))
    index = section.get("criterion_index", 0)
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < n_temps:
        return f"switching.criterion_index must be a column number 0…{n_temps - 1}"
    series = section.get("criterion_series", [0.0])
    if not isinstance(series, list) or not series or not all(_is_number(v) for v in series):
        return "switching.criterion_series must be a list of finite numbers"
    per_break = {"windows": n_breaks, "thresholds_c": n_breaks, "directions": n_breaks}
    per_sensor = {"temp_min_c": n_temps, "temp_max_c": n_temps}
    for key, length in {**per_break, **per_sensor}.items():
        if key in section and (not isinstance(section[key], list) or len(section[key]) != length):
            return f"switching.{key} must be a list of {length} entries"
    for key in ("thresholds_c", "temp_min_c", "temp_max_c"):
        if key in section and not all(_is_number(v) for v in section[key]):
            return f"switching.{key} must hold finite numbers"
    if "directions" in section and not all(v in (-1, 0, 1) for v in section["directions"]):
        return "switching.directions must hold -1, 0 or 1"
    if "windows" in section:
        for w in section["windows"]:
            if not (isinstance(w, list) and len(w) == 2 and all(isinstance(v, int) for v in w) and 1 <= w[0] <= w[1]):
                return "switching.windows must be [first, last] sample pairs with 1 ≤ first ≤ last"
    for key in ("noise_c", "margin_c", "comp_min_um", "comp_max_um", "rate_limit_um", "period_tolerance"):
        if key in section and not _is_number(section[key]):
            return f"switching.{key} must be a finite number"
    if "margin_c" in section and section["margin_c"] < 0:
        return "switching.margin_c must not be negative"
    if "rate_limit_um" in section and section["rate_limit_um"] <= 0:
        return "switching.rate_limit_um must be positive"
    if "comp_min_um" in section and "comp_max_um" in section and section["comp_min_um"] > section["comp_max_um"]:
        return "switching.comp_min_um must not exceed comp_max_um"
    if "hold_samples" in section and (not isinstance(section["hold_samples"], int) or section["hold_samples"] < 0):
        return "switching.hold_samples must be a whole number ≥ 0"
    if "temp_min_c" in section and "temp_max_c" in section:
        if any(lo > hi for lo, hi in zip(section["temp_min_c"], section["temp_max_c"])):
            return "switching.temp_min_c must not exceed temp_max_c"
    if SOURCE_RANGES_KEY in section:
        ranges = section[SOURCE_RANGES_KEY]
        if not isinstance(ranges, Mapping):
            return f"switching.{SOURCE_RANGES_KEY} must be an object: column -> [min, max]"
        for column, pair in ranges.items():
            if not (
                isinstance(pair, list) and len(pair) == 2 and all(_is_number(v) for v in pair) and pair[0] <= pair[1]
            ):
                return f"switching.{SOURCE_RANGES_KEY}['{column}'] must be [min, max] with min <= max"
    try:
        features = _parse_derived(model.get("derived_inputs", []))
    except InputError as exc:
        return str(exc)
    temps = model.get("temps", [])
    if 0 <= index < n_temps and temps[index] in {f.name for f in features}:
        return (
            f"switching.criterion_index names the derived input '{temps[index]}'; "
            "the switching criterion must be a measured input"
        )
    return None


def _reference_check(model: Mapping[str, Any]) -> str | None:
    """The ``reference`` key's problem: it must name no measured input (a derived input of it is fine)."""
    try:
        derived = {feature.name for feature in _parse_derived(model.get("derived_inputs", []))}
    except InputError:
        derived = set()
    return reference_problem(model.get("reference"), [name for name in model["temps"] if name not in derived])


def _parse_derived(entries: Any) -> list[Feature]:
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


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


# --------------------------------------------------------------------- the one place fields map to keys


def _frozen(value: Any) -> Any:
    """Lists as tuples, all the way down (mappings keep their keys)."""
    if isinstance(value, (list, tuple)):
        return tuple(_frozen(v) for v in value)
    if isinstance(value, Mapping):
        return {str(k): _frozen(v) for k, v in value.items()}
    return value


def _plain(value: Any) -> Any:
    """Tuples as lists, numpy scalars as Python numbers, objects by their ``to_dict``, all the way down (JSON)."""
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def _fields_to_dict(obj) -> dict[str, Any]:
    """Every field that is not None, in field order, then the keys this version does not know."""
    out = {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.name != "extra"}
    out = {key: value for key, value in out.items() if value is not None}
    out.update(_plain(obj.extra))
    return out


def _fields_from_dict(cls, data: Mapping[str, Any], nested: Mapping[str, Any] = {}):
    """The fields present in ``data`` (``nested``: key -> how to read it); unknown keys go to ``extra``."""
    names = [f.name for f in dataclasses.fields(cls) if f.name != "extra"]
    values = {}
    for key in names:
        if key in data:
            values[key] = nested[key](data[key]) if key in nested else _frozen(data[key])
    extra = {key: data[key] for key in data if key not in names}
    return cls(**values, extra=extra)


def as_model_file(model: ModelFile | Mapping[str, Any]) -> ModelFile:
    """Shorthand for :meth:`ModelFile.coerce`."""
    return ModelFile.coerce(model)


__all__ = [
    "FORMAT",
    "MAX_DELAY_SAMPLES",
    "ModelFile",
    "REQUIRED",
    "RULE_KEYS",
    "SOURCE_RANGES_KEY",
    "Switching",
    "as_model_file",
    "grouped_prediction",
    "model_problem",
    "rule_section_problem",
]
