"""The AR(1) routine, step by step, as the exported C, Structured Text and JSON runtimes perform it.

One call per sample (every ``sampling_period_s``) with the heat reading:

1. the first call after a reset outputs the start value ``E0`` (no update);
2. a reading that is not finite or outside ``[0, heat_max]`` holds the state
   (fault code 1, the output is the held value);
3. otherwise ``E := c1·E + C2(q)``; ``C2`` in double precision
   (:meth:`AR1File.c2_for`, the C library's ``pow``), rounded once to single
   precision in single mode, where ``E``, ``c1`` and the reading are IEEE
   singles (a PLC REAL) and the update is one product and one sum in single.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from groupfit.ar1.modelfile import AR1File
from groupfit.errors import InputError

FAULT_HEAT = 1
"""Fault code of a heat reading that is not finite or outside ``[0, heat_max]``: the state is held."""
PRECISIONS = ("double", "single")


@dataclass(frozen=True)
class AR1Replay:
    """Per sample: the fault code and the predicted error (µm)."""

    fault: np.ndarray
    prediction_um: np.ndarray


class AR1Rule:
    """The AR(1) routine of one model file, in double or single precision.

    Parameters
    ----------
    model : AR1File
    precision : {"double", "single"}
    """

    def __init__(self, model: AR1File, precision: str = "double"):
        if precision not in PRECISIONS:
            raise InputError(f"precision {precision!r}: choose one of {', '.join(PRECISIONS)}")
        self.model = model.checked()
        self.precision = precision
        self._real = np.float32 if precision == "single" else np.float64
        self.reset()

    def reset(self, initial_um: float = 0.0) -> None:
        """Start a run from ``initial_um`` (0 for a ``start = "zero"`` model)."""
        self.state = self._real(initial_um)
        self.started = False

    def step(self, heat: float) -> tuple[int, float]:
        """One sample: its fault code and the predicted error (µm)."""
        heat = float(self._real(heat))
        fault = 0 if np.isfinite(heat) and 0.0 <= heat <= self.model.heat_max else FAULT_HEAT
        if not self.started:
            self.started = True
        elif fault == 0:
            c2 = self._real(self.model.c2_for(heat))
            self.state = self._real(self._real(self.model.c1) * self.state) + c2
        return fault, float(self.state)

    def replay(self, heat, initial_um: float = 0.0) -> AR1Replay:
        """Every sample of a run after a reset to ``initial_um``."""
        self.reset(initial_um)
        with np.errstate(over="ignore", invalid="ignore"):
            results = [self.step(value) for value in np.asarray(heat, dtype=float)]
        fault, prediction = (np.array(column) for column in zip(*results)) if results else (np.zeros(0), np.zeros(0))
        return AR1Replay(fault=fault.astype(int), prediction_um=prediction.astype(float))


__all__ = ["AR1Replay", "AR1Rule", "FAULT_HEAT", "PRECISIONS"]
