"""What the tests share: independent references, fixtures' builders and small writers."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pytest

from groupfit.io import atomic_write_text, to_json
from groupfit.model import ModelFile

SHARED_DATA = Path(__file__).resolve().parents[3] / "shared" / "data"
"""The measured data next to the project (``../shared/data``), absent from a fresh clone: tests that read it skip."""


def write_model(model: ModelFile | Mapping[str, Any], path: str | Path) -> None:
    """Write a model file as given, without the checks of :meth:`ModelFile.save`: tests write broken files too."""
    atomic_write_text(path, to_json(model.to_dict() if isinstance(model, ModelFile) else model))


def same_run(run, plain, *, time: bool = True) -> None:
    """Assert that ``run`` holds the readings of ``plain`` (the same run read from its plain form)."""
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.error, plain.error)
    if time:
        np.testing.assert_array_equal(run.time, plain.time)
    assert run.period == pytest.approx(plain.period)
