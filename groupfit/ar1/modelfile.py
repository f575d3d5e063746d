"""The AR(1) model file: ``"format": "groupfit-model/1"``, ``"kind": "ar1"``.

The physics first-order model of :mod:`groupfit.models.ar1` as ``groupfit fit
--model ar1`` writes it and ``replay`` and ``export`` read it::

    E(0) = E0,   E(k) = c1·E(k−1) + C2(q_k)

``q_k`` is the heat reading (column ``heat``) during the interval that ends at
sample k, taken every ``sampling_period_s``; ``C2(q)`` is ``c2_um[i]`` at a
fitted level ``levels[i]``, 0 at q = 0, and at any other q the nearest level's
``c2_um`` times ``(q / level)^heat_exponent`` (the heat law). A reading
outside ``[0, heat_max]`` or not finite holds the state. ``start`` says what
E0 is: ``"zero"`` (the paper's ΔL(0) = 0) or ``"measured"`` (the error
measured when the routine starts).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from groupfit.errors import InputError
from groupfit.io import atomic_write_text, read_json_file, to_json
from groupfit.model import _fields_from_dict, _fields_to_dict
from groupfit.model_checks import COEFFICIENT_LIMIT, FORMAT
from groupfit.switching_checks import RULE_LIMIT
from groupfit.training_checks import expectation_problem

KIND = "ar1"
STARTS = ("zero", "measured")
FITS = ("one_step", "free_run", "closed_form")
MAX_HEAT_EXPONENT = 4.0
"""Largest heat-law exponent a file may hold (5/3 for bearing heat against speed, 1 for a heat flux)."""
MAX_HEAT_RATIO = 1.0e6
"""Largest ``heat_max / levels[0]``: keeps every C2 of the heat law finite in single precision."""
HEAT_MARGIN = 2.0
"""Default valid heat range: 0 to this many times the largest fitted level."""


def is_ar1(data: Any) -> bool:
    """Whether a model file object is an AR(1) model."""
    return isinstance(data, Mapping) and data.get("kind") == KIND


def is_ar1_file(path: str | Path) -> bool:
    """Whether ``path`` is a readable AR(1) model file (anything else: False, for its own loader to judge)."""
    try:
        return is_ar1(read_json_file(path))
    except InputError:
        return False


@dataclass(frozen=True, kw_only=True)
class AR1File:
    """An AR(1) model as its file holds it; field names are the file's keys."""

    format: str = FORMAT
    kind: str = KIND
    sampling_period_s: float
    heat: str
    error: str | None = None
    c1: float
    levels: tuple[float, ...]
    c2_um: tuple[float, ...]
    heat_exponent: float
    heat_max: float
    start: str
    fit: str
    training: Mapping[str, Any] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def from_dict(cls, data: Any, source: str | Path | None = None) -> "AR1File":
        """Check an AR(1) model file object and build the model; InputError names what is wrong."""
        problem = ar1_problem(data)
        if problem:
            raise InputError((f"{source}: " if source is not None else "") + problem)
        return _fields_from_dict(cls, data)

    def to_dict(self) -> dict[str, Any]:
        return _fields_to_dict(self)

    @classmethod
    def load(cls, path: str | Path) -> "AR1File":
        return cls.from_dict(read_json_file(path), source=Path(path))

    def checked(self) -> "AR1File":
        problem = ar1_problem(json.loads(to_json(self.to_dict())))
        if problem:
            raise InputError(f"invalid AR(1) model: {problem}")
        return self

    def save(self, path: str | Path) -> None:
        """Write the model file (checked first: an invalid model is never written)."""
        atomic_write_text(path, to_json(self.checked().to_dict()))

    def replace(self, **changes) -> "AR1File":
        return dataclasses.replace(self, **changes)

    def c2_for(self, heat: float) -> float:
        """C2 (µm) of one heat reading in ``[0, heat_max]``, in double precision, as every runtime computes it."""
        if heat == 0.0:
            return 0.0
        nearest = 0
        for i, level in enumerate(self.levels):
            if abs(level - heat) < abs(self.levels[nearest] - heat):
                nearest = i
        level = self.levels[nearest]
        if heat == level:
            return self.c2_um[nearest]
        return self.c2_um[nearest] * math.pow(heat / level, self.heat_exponent)


def _positive(value: Any, limit: float = RULE_LIMIT) -> bool:
    return (
        isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and 0 < value <= limit
    )


def ar1_problem(data: Any) -> str | None:
    """What is wrong with an AR(1) model file object, or None."""
    if not isinstance(data, Mapping):
        return "an AR(1) model file holds a JSON object"
    required = [f.name for f in dataclasses.fields(AR1File) if f.default is dataclasses.MISSING and f.name != "extra"]
    missing = [key for key in required if key not in data]
    if missing:
        return f"AR(1) model: key(s) {', '.join(missing)} missing; write it with groupfit fit --model ar1"
    if data.get("format") != FORMAT or data.get("kind") != KIND:
        return f"format {data.get('format')!r}, kind {data.get('kind')!r}: expected {FORMAT!r}, {KIND!r}"
    if not _positive(data["sampling_period_s"]):
        return f"sampling_period_s = {data['sampling_period_s']!r}: give a positive number of seconds"
    for key in ("heat", "error"):
        if data.get(key) is not None and (not isinstance(data[key], str) or not data[key]):
            return f"{key} = {data[key]!r}: a column name"
    problem = _coefficients_problem(data) or _heat_problem(data)
    if problem:
        return problem
    if data["start"] not in STARTS:
        return f"start = {data['start']!r}: one of {', '.join(STARTS)}"
    if data["fit"] not in FITS:
        return f"fit = {data['fit']!r}: one of {', '.join(FITS)}"
    training = data.get("training")
    if training is not None and not isinstance(training, Mapping):
        return "training: a JSON object"
    return expectation_problem(training or {}) or _recordings_problem(training or {})


def _recordings_problem(training: Mapping[str, Any]) -> str | None:
    """``training.recordings``: a list of objects, each with the file's SHA-256 as a string."""
    entries = training.get("recordings", [])
    if not isinstance(entries, list) or not all(
        isinstance(entry, Mapping) and isinstance(entry.get("sha256"), str) for entry in entries
    ):
        return f"training.recordings = {entries!r}: a list of {{path, sha256}} objects (the modelling files)"
    return None


def _coefficients_problem(data: Mapping[str, Any]) -> str | None:
    """C1 stable, the levels positive and increasing, one finite C2 per level."""
    c1 = data["c1"]
    if not (isinstance(c1, (int, float)) and not isinstance(c1, bool) and math.isfinite(c1) and 0 < c1 < 1):
        return f"c1 = {c1!r}: a stable AR(1) model has 0 < c1 < 1"
    levels, c2 = data["levels"], data["c2_um"]
    if not isinstance(levels, list) or not levels or not all(_positive(v) for v in levels):
        return f"levels = {levels!r}: one or more positive heat levels, at most {RULE_LIMIT:g}"
    if any(b <= a for a, b in zip(levels, levels[1:])):
        return f"levels = {levels!r}: strictly increasing"
    if not isinstance(c2, list) or len(c2) != len(levels):
        return f"c2_um: one value per level ({len(levels)})"
    for i, value in enumerate(c2):
        if not (
            isinstance(value, (int, float))
            and not isinstance(value, bool)
            and math.isfinite(value)
            and abs(value) <= COEFFICIENT_LIMIT
        ):
            return f"c2_um[{i}] = {value!r}: a finite number of at most {COEFFICIENT_LIMIT:g} µm"
    return None


def _heat_problem(data: Mapping[str, Any]) -> str | None:
    """The heat law's exponent and the valid heat range."""
    levels = data["levels"]
    if not _positive(data["heat_exponent"], MAX_HEAT_EXPONENT):
        return f"heat_exponent = {data['heat_exponent']!r}: in (0, {MAX_HEAT_EXPONENT:g}]"
    if not _positive(data["heat_max"]) or data["heat_max"] < levels[-1]:
        return f"heat_max = {data['heat_max']!r}: at least the largest level ({levels[-1]:g}), at most {RULE_LIMIT:g}"
    if data["heat_max"] / levels[0] > MAX_HEAT_RATIO:
        return (
            f"heat_max = {data['heat_max']!r} is more than {MAX_HEAT_RATIO:g} times the smallest level "
            f"({levels[0]:g}): the heat law would leave single precision; lower heat_max"
        )
    return None


__all__ = ["AR1File", "FITS", "HEAT_MARGIN", "KIND", "STARTS", "ar1_problem", "is_ar1", "is_ar1_file"]
