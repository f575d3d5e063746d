"""The AR(1) routine's step against the run's sampling period: a routine called every k samples."""

from __future__ import annotations

import math

import numpy as np

from groupfit.data import PERIOD_TOLERANCE
from groupfit.errors import InputError


def decimation_step(period_s: float, dtau_s: float | None, *, what: str = "--period") -> int:
    """How many samples of the run make one AR(1) step of ``dtau_s`` seconds (1 without ``dtau_s``).

    ``what`` names the step in the error (the option, or the model's period).
    """
    if dtau_s is None:
        return 1
    if not (math.isfinite(dtau_s) and dtau_s > 0):
        raise InputError(f"{what} {dtau_s!r}: give a positive number of seconds")
    step = dtau_s / period_s
    if round(step) < 1 or abs(step - round(step)) > PERIOD_TOLERANCE * step:
        raise InputError(
            f"{what} {dtau_s:g} s is not a whole multiple of the run's sampling period {period_s:g} s; "
            f"resample the run, or choose a multiple such as {2 * period_s:g} or {4 * period_s:g}"
        )
    return int(round(step))


def decimate(values: np.ndarray, step: int) -> np.ndarray:
    """Every ``step``-th row from the first: the run as a routine called every ``step`` samples sees it.

    The heat reading at a kept row is the level during the interval that ends there (the raw row's value).
    """
    return np.asarray(values)[::step]
