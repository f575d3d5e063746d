"""The error to expect on the next run of an AR(1) model: forward chaining over the steps of its heat column.

As for the grouped models (:mod:`groupfit.heldout.nextrun`), the estimate
imitates a next run, which gives the model no help: the run is cut where its
heat column changes (a long stretch into pieces of at most a sixth of the run,
:func:`groupfit.heldout.folds.condition_segments`; a heat column that never
changes leaves equal blocks of time). For every segment that starts after
:data:`~groupfit.heldout.nextrun.MIN_TRAIN_FRACTION` of the run, the AR(1)
model is fitted on the run before the segment, as ``fit --model ar1`` fits it,
and its routine (:class:`~groupfit.ar1.rule.AR1Rule`, the free run from the
run's start: a level the prefix never saw by the heat law, a reading beyond its
``heat_max`` held as on the controller) is replayed over the prefix and the
segment; only the segment is scored, and the squared errors are pooled over the
segments. A prefix the AR(1) fit refuses (no heat level above 0, a free run
that would not settle) scores no segment.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import pandas as pd

from groupfit.ar1.modelfile import AR1File
from groupfit.ar1.rule import AR1Rule
from groupfit.errors import InputError
from groupfit.heldout.expect import NextRunExpectation, trust_notes
from groupfit.heldout.folds import condition_segments, setting_values
from groupfit.heldout.nextrun import (
    FORWARD,
    MIN_TRAIN_FRACTION,
    NO_OPERATING_COLUMN,
    NextRunScores,
    leaves_one_condition,
)

CANDIDATE = "AR(1)"


def heat_segments(heat: np.ndarray, heat_name: str) -> tuple[list[int], str, int, np.ndarray | None]:
    """First sample of every segment of the run, how they were cut, how many distinct heat levels the run holds,
    and each sample's level as a code (1 level and no codes: the heat never changes, and the segments are blocks
    of time)."""
    frame = pd.DataFrame({heat_name: heat})
    labels = condition_segments(frame, [heat_name])
    starts = [0, *(np.flatnonzero(np.diff(labels) != 0) + 1).tolist()]
    levels = setting_values(frame, heat_name)
    distinct, codes = np.unique(levels, return_inverse=True)
    if len(distinct) == 1:
        return starts, f"the run cut into {len(starts)} equal blocks, {NO_OPERATING_COLUMN}", 1, None
    return starts, f"changes of {heat_name}", len(distinct), codes


def ar1_forward_chaining(
    heat: np.ndarray,
    error: np.ndarray,
    predict: Callable[[int, int], np.ndarray],
    *,
    heat_name: str,
    min_train: float = MIN_TRAIN_FRACTION,
) -> NextRunScores | None:
    """The AR(1) model's squared errors on every scored segment (module docstring); None when no segment can be
    scored.

    ``predict(a, b)`` fits the model on the first ``a`` samples and returns its free run over the first ``b``
    (from the run's start), or raises :class:`~groupfit.errors.InputError` when the prefix cannot be fitted;
    ``heat`` and ``error`` are at the model's step.
    """
    heat, error = np.asarray(heat, dtype=float), np.asarray(error, dtype=float)
    n = len(error)
    starts, how, conditions, codes = heat_segments(heat, heat_name)
    edges = [*starts, n]
    folds = [(a, b) for a, b in zip(edges[:-1], edges[1:]) if a >= min_train * n and b > a]
    sse, counts = [], []
    for a, b in folds:
        try:
            prediction = predict(a, b)[a:b]
        except InputError:
            continue
        residual = error[a:b] - prediction
        scored = np.isfinite(residual)
        if scored.any():
            sse.append(float(np.sum(residual[scored] ** 2)))
            counts.append(int(scored.sum()))
    if not sse:
        return None
    return NextRunScores(
        candidates=(CANDIDATE,),
        sse=np.array([sse]),
        counts=np.array(counts),
        kind=FORWARD,
        segments=how,
        n_samples=n,
        n_conditions=conditions,
        blocks_of_time=conditions == 1,
        leaves_one_condition=leaves_one_condition(folds, codes),
        physics_model=True,
    )


def file_predictor(
    heat: np.ndarray, error: np.ndarray, fit: Callable[[np.ndarray, np.ndarray], AR1File]
) -> Callable[[int, int], np.ndarray]:
    """``predict(a, b)`` of a deployable model: ``fit(heat, error)`` on the prefix (as ``fit --model ar1``
    fits it), its routine (:class:`~groupfit.ar1.rule.AR1Rule`) replayed as on the controller."""

    def predict(a: int, b: int) -> np.ndarray:
        model = fit(heat[:a], error[:a])
        initial = float(error[0]) if model.start == "measured" else 0.0
        return AR1Rule(model).replay(heat[:b], initial_um=initial).prediction_um

    return predict


def expect_ar1(
    heat: np.ndarray, error: np.ndarray, predict: Callable[[int, int], np.ndarray], *, heat_name: str
) -> NextRunExpectation | None:
    """The AR(1) model's expected next-run RMS, calibrated as the grouped models' figure is
    (:mod:`groupfit.heldout.calibration`); None when no segment can be scored."""
    scores = ar1_forward_chaining(heat, error, predict, heat_name=heat_name)
    return None if scores is None else NextRunExpectation(scores, 0, trust_notes(scores))


__all__ = ["CANDIDATE", "ar1_forward_chaining", "expect_ar1", "file_predictor", "heat_segments"]
