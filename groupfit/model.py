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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Self

import numpy as np

from groupfit.data import DEFAULT_TIME
from groupfit.errors import InputError
from groupfit.features import Feature, derived_matrix
from groupfit.grouping import bumpless, serving_group_index
from groupfit.io import atomic_write_text, read_json_file, to_json
from groupfit.model_checks import COEFFICIENT_LIMIT, FORMAT, MAX_POSITION_ORDER, model_problem
from groupfit.model_recalibration import Recalibration
from groupfit.reference import referenced
from groupfit.switching_checks import MAX_DELAY_SAMPLES, SOURCE_RANGES_KEY, parse_derived, rule_section_problem

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


class _Section:
    """A section of the model file, read from and written to its JSON object; unknown keys are kept in ``extra``."""

    def to_dict(self) -> dict[str, Any]:
        return _fields_to_dict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Self:
        return _fields_from_dict(cls, data)


@dataclass(frozen=True, kw_only=True)
class Switching(_Section):
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
    blend_samples: int | None = None
    """Bumpless transfer: samples over which the output moves from the old group's prediction to the new
    group's after a switch (``fit`` writes the overlap n); absent (files written before it): 0, a hard switch."""
    source_ranges: Mapping[str, tuple[float, float]] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @property
    def has_rule(self) -> bool:
        """Whether every rule parameter is present."""
        return all(getattr(self, key) is not None for key in RULE_KEYS)

    def with_rule(self, parameters: Mapping[str, Any]) -> "Switching":
        """This section with the rule parameters of :func:`groupfit.runtime.rule_parameters` (keys of RULE_KEYS)."""
        return dataclasses.replace(self, **{key: _frozen(value) for key, value in parameters.items()})


@dataclass(frozen=True, kw_only=True)
class Position(_Section):
    """The ``position`` section: the error's dependence on an axis position (docs/position.md).

    ``E(P, T) = K0(T) + c1(T)·d + … + c_order(T)·d^order`` with ``d = P − P0``
    (mm): ``K0(T)`` is the model's ``coefficients`` row of the serving group,
    and ``coefficients[g][k − 1]`` the row (constant first when the model has
    an intercept, then one per input) of ``c_k`` in group ``g``. Order 1 is
    SINUMERIK's ``K0 + tanβ·(P − P0)`` (``c1`` = tanβ in µm per mm). A position
    outside ``travel_mm`` is clamped to it at run time (and flagged).
    ``coefficient_ranges``: per power, ``[min, max]`` of ``c_k(T)`` over the
    modelling run (what a position table must cover).
    """

    column: str
    p0_mm: float
    order: int
    travel_mm: tuple[float, float]
    coefficients: tuple[tuple[tuple[float, ...], ...], ...]
    coefficient_ranges: tuple[tuple[float, float], ...] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def coefficient_array(self, *, intercept: bool = True) -> np.ndarray:
        """(G, order, M+1): the rows of ``c_1 … c_order`` per group, constant first (0 without an intercept)."""
        rows = np.asarray(self.coefficients, dtype=float)
        if not intercept:
            rows = np.concatenate([np.zeros(rows.shape[:2] + (1,)), rows], axis=2)
        return rows


@dataclass(frozen=True, kw_only=True)
class DeadBand(_Section):
    """The ``dead_band`` section: no update while every measured input is within ``threshold_c`` of ``reference``.

    Seed 001's rule: the compensation is only updated while some
    ``|T_i − T_ref| > threshold_c``; inside the band the rule keeps the last
    target it computed outside it (0 before the first).
    """

    reference: str
    threshold_c: float
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)


def time_column(model: "ModelFile | Mapping[str, Any]") -> str:
    """The time column the model was fitted with, kept under ``training.time`` (default ``time_s``)."""
    training = model.training if isinstance(model, ModelFile) else model.get("training")
    return str((training or {}).get("time") or DEFAULT_TIME)


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
    ridge_alpha: float | None = None
    """The ridge penalty the coefficients were fitted with (:mod:`groupfit.models.ridge`); absent: least squares."""
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
    position: Position | None = None
    dead_band: DeadBand | None = None
    recalibration: Recalibration | None = None
    """How probe checks correct the compensation at run time (:mod:`groupfit.model_recalibration`)."""
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    # ----------------------------------------------------------------- reading and writing

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | Path | None = None) -> "ModelFile":
        """Check a model file object and build the model; InputError names what is wrong (and ``source``)."""
        prefix = f"{source}: " if source is not None else ""
        problem = model_file_problem(data)
        if problem:
            raise InputError(prefix + problem)
        nested = {
            "switching": Switching.from_dict,
            "derived_inputs": lambda v: tuple(parse_derived(v)),
            "position": Position.from_dict,
            "dead_band": DeadBand.from_dict,
            "recalibration": lambda v: _fields_from_dict(Recalibration, v),
        }
        return _fields_from_dict(cls, data, nested)

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of the file: every present key, in the file's order, plain lists and numbers."""
        return _fields_to_dict(self)

    @classmethod
    def load(cls, path: str | Path) -> "ModelFile":
        """Read and check a model file."""
        return cls.from_dict(read_json_file(path), source=Path(path))

    def save(self, path: str | Path) -> None:
        """Write the model file (checked first: an invalid model is never written)."""
        atomic_write_text(path, to_json(self.checked().to_dict()))

    def checked(self) -> "ModelFile":
        """This model, after the checks of :func:`model_problem` on its file object; InputError otherwise."""
        problem = model_file_problem(json.loads(to_json(self.to_dict())))
        if problem:
            raise InputError(f"invalid model: {problem}")
        return self

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

    def predict(self, inputs, groups: np.ndarray | None = None, *, transfer: bool = False) -> np.ndarray:
        """Predicted error of every row of the (N, M) input matrix.

        Each row is served by ``groups`` (0-based, e.g. from the run-time rule)
        or, by default, by the group that serves its sample index offline.
        ``transfer``: with the run-time rule's bumpless transfer after each
        switch (``switching.blend_samples``), as the controller computes it.
        """
        inputs = np.asarray(inputs, dtype=float)
        if inputs.ndim != 2 or inputs.shape[1] != len(self.temps):
            raise InputError(f"inputs of shape {inputs.shape}: the model has {len(self.temps)} inputs")
        if groups is None:
            groups = self.serving_groups(len(inputs))
        matrix = self.coefficient_matrix()
        prediction = grouped_prediction(matrix[:, 0], matrix[:, 1:], inputs, groups)
        return self._transferred(prediction, groups) if transfer else prediction

    def _transferred(self, prediction: np.ndarray, groups) -> np.ndarray:
        """``prediction`` with the bumpless transfer after each switch (:func:`groupfit.grouping.bumpless`)."""
        return bumpless(prediction, groups, int(self.switching.blend_samples or 0))

    def predict_position(
        self, inputs, positions, groups: np.ndarray | None = None, *, transfer: bool = False
    ) -> np.ndarray:
        """E(P, T) of every row: ``K0(T)`` (:meth:`predict`) plus the position polynomial in ``d = P − P0``.

        Positions outside the travel are clamped to it, as the run-time rule
        does. The polynomial is evaluated as the rule does (Horner's scheme,
        highest power first). A model without a position section: :meth:`predict`.
        """
        k0 = self.predict(inputs, groups)
        if self.position is None:
            return k0
        inputs = np.asarray(inputs, dtype=float)
        if groups is None:
            groups = self.serving_groups(len(inputs))
        low, high = self.position.travel_mm
        d = np.clip(np.asarray(positions, dtype=float), low, high) - self.position.p0_mm
        rows = self.position.coefficient_array(intercept=self.intercept)[np.asarray(groups)]
        terms = rows[:, :, 0] + np.einsum("ikj,ij->ik", rows[:, :, 1:], inputs)
        poly = terms[:, -1]
        for k in range(terms.shape[1] - 2, -1, -1):
            poly = poly * d + terms[:, k]
        return self._transferred(k0 + poly * d, groups) if transfer else k0 + poly * d

    def inputs(self, frame, source: str = "the run") -> np.ndarray:
        """The model's input matrix from a table (DataFrame-like): measured columns and derived inputs.

        Derived inputs use the model's sampling period, as the run-time rule
        does (a run's own period may differ from it by up to 1 %).
        """
        derived = self.derived
        columns = []
        for name in self.temps:
            if name in derived:
                columns.append(derived_matrix([derived[name]], frame, self.sampling_period_s, source)[:, 0])
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


def model_file_problem(data: Any) -> str | None:
    """What is wrong with a model file object (its JSON form), or None: every check of :func:`model_problem`,
    the keys of :data:`REQUIRED` included."""
    return model_problem(data, REQUIRED)


def _frozen(value: Any) -> Any:
    """Lists as tuples, all the way down (mappings keep their keys)."""
    if isinstance(value, (list, tuple)):
        return tuple(_frozen(v) for v in value)
    if isinstance(value, Mapping):
        return {str(k): _frozen(v) for k, v in value.items()}
    return value


def _plain(value: Any) -> Any:
    """Tuples as lists, numpy scalars as Python numbers, objects by their ``to_dict``, all the way down (JSON)."""
    if isinstance(value, Recalibration):  # a section of its own module: its fields map to keys here too
        return _fields_to_dict(value)
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
    """Every required field and every optional one that is not None, in field order, then unknown keys."""
    fields = [f for f in dataclasses.fields(obj) if f.name != "extra"]
    required = {f.name for f in fields if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    out = {f.name: _plain(getattr(obj, f.name)) for f in fields}
    out = {key: value for key, value in out.items() if value is not None or key in required}
    out.update(_plain(obj.extra))
    return out


def _fields_from_dict(cls, data: Mapping[str, Any], nested: Mapping[str, Any] = {}):
    """The fields present in ``data`` (``nested``: key -> how to read it); unknown keys go to ``extra``."""
    names = [f.name for f in dataclasses.fields(cls) if f.name != "extra"]
    values = {}
    for key in names:
        if key in data and not (key in nested and data[key] is None):  # an optional section of null is absent
            values[key] = nested[key](data[key]) if key in nested else _frozen(data[key])
    extra = {key: data[key] for key in data if key not in names}
    return cls(**values, extra=extra)


__all__ = [
    "COEFFICIENT_LIMIT",
    "DeadBand",
    "FORMAT",
    "MAX_POSITION_ORDER",
    "Position",
    "Recalibration",
    "MAX_DELAY_SAMPLES",
    "ModelFile",
    "REQUIRED",
    "RULE_KEYS",
    "SOURCE_RANGES_KEY",
    "Switching",
    "grouped_prediction",
    "model_file_problem",
    "rule_section_problem",
]
