"""What the tests of validation runs with faulty readings share: a verb's ``--json`` result, and the check that
``diagnose``'s figures on a validation run are ``replay``'s."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, Mapping

import pytest

from groupfit.cli import main


def run_json(capsys, *args) -> dict:
    """The ``--json -`` result of ``groupfit ARGS``, which must exit 0."""
    capsys.readouterr()
    assert main([str(a) for a in [*args, "--json", "-"]]) == 0
    return json.loads(capsys.readouterr().out)


def assert_judged_as_replayed(
    capsys, report: Mapping, models: Mapping[str, Path], run: Path, unscored: Callable[[Path], int]
) -> None:
    """``diagnose``'s ``report`` gives, for each of its ``models`` (``"before"``, ``"after"``: model files), the
    RMS and the largest error ``replay`` of that file gives on validation ``run``, where replay leaves
    ``unscored(model file)`` samples in sensor fault."""
    for when, path in models.items():
        replayed = run_json(capsys, "replay", path, "--data", run)
        assert replayed["faults"]["sensor_fault_samples"] == unscored(path)
        assert report[when]["validate"]["rms_um"] == pytest.approx(replayed["rms_um"], rel=0, abs=1e-6)
        assert report[when]["validate"]["max_um"] == pytest.approx(replayed["max_um"], rel=0, abs=1e-6)
