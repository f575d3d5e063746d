"""Whether a model takes the fast-response stage, and with which time constant: decided with simulated checks.

The stage (:mod:`groupfit.fast_response`) is for a compensation with probe
checks: what it removes changes faster than checks come. So it is judged as
the recalibration filter is (:mod:`groupfit.recalibration_tuning`): the model
and the stage are refitted, in their two steps, on the first part of each
modelling run; checks every 15 min … 2 h are replayed on the rest through
every candidate filter; each model is scored by its best filter's RMS. The
stage is kept, with the time constant that scores best, only when it lowers
the mean over the check intervals of log(RMS) by more than :data:`MARGIN`
and does not raise the held-out RMS without checks by more than
:data:`~groupfit.recalibration_tuning.INDIFFERENCE`: the stage must not move
the model's level on a run it has not seen.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from groupfit.fast_response import stage_columns, with_stage, without_stage
from groupfit.model import ModelFile
from groupfit.recalibration_tuning import INDIFFERENCE, Tuning, choose_recalibration

TAUS_S = (300.0, 600.0, 1200.0)
"""Time constants of the low-pass the sensors' fast swings are taken against."""
MARGIN = 0.05
"""The least mean log-RMS gain with checks (about 5 %) the stage must show. Wider than the filters'
indifference (0.02): the stage fits one more weight per sensor, where the filters differ in a few noise
levels. On r100_ambient_rises of the probe-pairs bench a stage that gained 0.043 on held-out stretches cost
30 % on the next run."""
MIN_PERIODS_PER_TAU = 2.0
"""A time constant shorter than this many sampling periods is not tried."""


def choose_stage(model: ModelFile, runs: Sequence, method: str) -> tuple[ModelFile, Tuning, Tuning | None]:
    """The model with or without the stage, its filter's tuning, and the tuning without the stage when the stage
    was kept (None otherwise).

    ``runs``: (frame, error) pairs of the modelling runs. ``method``: the
    recalibration method asked for (``none``: no checks, no stage).
    """
    base = without_stage(model)
    base_tuning = choose_recalibration(base, runs, method=method)
    if method == "none" or not stage_columns(base) or not base_tuning.rms_chosen_um:
        return base, base_tuning, None
    best, best_tuning, best_score = base, base_tuning, -MARGIN
    for tau in TAUS_S:
        if tau < MIN_PERIODS_PER_TAU * model.sampling_period_s:
            continue
        candidate = with_stage(base, runs, tau)
        if candidate is None:
            continue
        tuning = choose_recalibration(candidate, runs, method=method)
        score = _score(tuning, base_tuning)
        if score < best_score:
            best, best_tuning, best_score = candidate, tuning, score
    return best, best_tuning, (base_tuning if best is not base else None)


def _score(tuning: Tuning, base: Tuning) -> float:
    """Mean log RMS with checks against the model without the stage (+inf: not comparable, or the level moves)."""
    if len(tuning.rms_chosen_um) != len(base.rms_chosen_um) or not tuning.rms_chosen_um:
        return math.inf
    with_checks = np.asarray(tuning.rms_chosen_um) / np.asarray(base.rms_chosen_um)
    if not np.all(np.isfinite(with_checks) & (with_checks > 0)):
        return math.inf
    if not (tuning.rms_none_um <= base.rms_none_um * math.exp(INDIFFERENCE)):
        return math.inf
    return float(np.mean(np.log(with_checks)))


__all__ = ["MARGIN", "TAUS_S", "choose_stage"]
