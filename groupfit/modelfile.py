"""Compatibility: the model file as a plain ``dict`` (callers written before :class:`groupfit.model.ModelFile`).

New code reads and writes :class:`groupfit.model.ModelFile`; these helpers
convert at the edge. I/O helpers live in :mod:`groupfit.io`, metrics in
:mod:`groupfit.metrics`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from groupfit.io import atomic_write_text, to_json
from groupfit.metrics import error_metrics
from groupfit.model import FORMAT, REQUIRED, ModelFile


def load_model(path: str | Path) -> dict[str, Any]:
    """Read and check a model file; its JSON object."""
    return ModelFile.load(path).to_dict()


def save_model(model: ModelFile | Mapping[str, Any], path: str | Path) -> None:
    """Write a model (a model file object is written as given, unchecked)."""
    atomic_write_text(path, to_json(model.checked().to_dict() if isinstance(model, ModelFile) else model))


def model_to_dict(model, run, criterion: str | None = None) -> dict[str, Any]:
    """The model file object of a :class:`GroupedRegressor` fitted on ``run``."""
    return model.to_model_file(run, criterion).to_dict()


def estimator_from_dict(model: ModelFile | Mapping[str, Any]):
    """A fitted :class:`GroupedRegressor` with the model file's groups and coefficients."""
    from groupfit.models.grouped import GroupedRegressor

    return GroupedRegressor.from_model_file(model)


__all__ = [
    "FORMAT",
    "REQUIRED",
    "atomic_write_text",
    "error_metrics",
    "estimator_from_dict",
    "load_model",
    "model_to_dict",
    "save_model",
    "to_json",
]
