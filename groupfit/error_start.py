"""An error logged from another zero than the run's start, read as the drift since it: ``--error COLUMN-start``.

A thermal error is the drift of the tool against the work since the test
began (ISO 230-3 measures it from the first reading, the machine cold). Many
logs hold something else: a displacement sensor's reading with its stand-off
distance in it, a 3-D printer's probe position counted from the machine's
zero after a re-homing (``mcu_pos_z``). Each new mounting or homing moves that
zero, so a model fitted on one run is off on the next by the difference, far
more than any thermal drift. ``--error 'COLUMN-start'`` (``mcu_pos_z*2.5-start``
or ``mcu_pos_z-start*2.5`` with a factor) reads each run's error less its first reading. The model file
keeps the name as its ``error``, so ``replay``, ``diagnose`` and ``compare``
read a next run the same way.

A file that is the rest of a recording (its clock goes on from the other's,
``--continues``, or a modelling file it continues) is not a new start: its
error is taken from the recording's first reading, as on the controller
(:func:`groupfit.continuation.picked_up`). ``fit`` keeps that reading of every modelling file in
``training.recordings`` (:data:`ZERO_KEY`), so that the rest of a modelling file
no longer at hand still reads from it.
"""

from __future__ import annotations

import re

import numpy as np

START_SUFFIX = re.compile(r"\s*-\s*start\s*$", re.IGNORECASE)
START_BEFORE_FACTOR = re.compile(r"^(?P<column>.*\S)\s*-\s*start\s*(?P<factor>\*\s*\S+)\s*$", re.IGNORECASE)
ZERO_KEY = "error_zero_um"
"""The reading (µm, as logged) the error of a modelling file's last run was taken from (``training.recordings``): what
the rest of the recording reads its error from."""


def logged_spec(name: str | None) -> str | None:
    """The column (or ``COLUMN*K``) a name that asks for the drift since the start reads (``COLUMN-start``,
    ``COLUMN*K-start`` or ``COLUMN-start*K``); None for any other."""
    if not isinstance(name, str):
        return None
    before = START_BEFORE_FACTOR.match(name)
    if before:
        return f"{before.group('column')}{before.group('factor')}"
    spec = START_SUFFIX.sub("", name)
    return spec if spec != name and spec.strip() else None


def is_from_start(name: str | None) -> bool:
    """Whether ``name`` asks for the error less the run's first reading (``COLUMN-start``)."""
    return logged_spec(name) is not None


def first_reading(values: np.ndarray) -> float | None:
    """The first finite value, None when there is none."""
    finite = np.flatnonzero(np.isfinite(values))
    return float(values[finite[0]]) if finite.size else None


def from_start(values: np.ndarray) -> np.ndarray:
    """``values`` less their first finite value."""
    first = first_reading(values)
    return values if first is None else values - first


__all__ = ["ZERO_KEY", "first_reading", "from_start", "is_from_start", "logged_spec"]
