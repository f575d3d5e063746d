"""What the tests share: independent references, fixtures' builders and small writers."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from groupfit.io import atomic_write_text, to_json
from groupfit.model import ModelFile

SHARED_DATA = Path(__file__).resolve().parents[3] / "shared" / "data"
"""The measured data next to the project (``../shared/data``), absent from a fresh clone: tests that read it skip."""


def write_model(model: ModelFile | Mapping[str, Any], path: str | Path) -> None:
    """Write a model file as given, without the checks of :meth:`ModelFile.save`: tests write broken files too."""
    atomic_write_text(path, to_json(model.to_dict() if isinstance(model, ModelFile) else model))
