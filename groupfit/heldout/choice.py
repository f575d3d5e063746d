"""The candidate chosen by its expected next-run error: the simplest one the estimate cannot tell from the best."""

from __future__ import annotations

from typing import Sequence

import numpy as np

RMS_TOLERANCE = 2.0
"""A more complex candidate is taken only when its expected RMS is below the simpler one's by more than this
factor: the accuracy the next-run estimate is held to (within a factor of 2 of the next run). On the
calibration panel (``bench/bench_next_run.py``, 34 pairs and 5 cuts of the measured test) the chosen model came
within 1.5× of the best p on the next run on 92 % of the 39 pairs with this tolerance (87 % before the estimate
counted the compensation's clamp), 79 % with none (before it too)."""


def one_standard_error_choice(
    mean: Sequence[float], standard_error: Sequence[float], *, rms_tolerance: float = 1.0
) -> int:
    """Index of the simplest candidate within one standard error of the best, or within ``rms_tolerance`` of it.

    Candidates are ordered from the simplest to the most complex. The best is the
    least ``mean`` (the expected mean squared error); the choice is the first
    candidate whose mean is at most the best's mean plus the best's standard error
    (Hastie, Tibshirani and Friedman, *The Elements of Statistical Learning*, §7.10)
    or at most ``rms_tolerance²`` times the best's mean (its root within
    ``rms_tolerance`` times the best's), whichever allows more.
    """
    mean = np.asarray(mean, dtype=float)
    standard_error = np.asarray(standard_error, dtype=float)
    if mean.ndim != 1 or len(mean) == 0 or mean.shape != standard_error.shape:
        raise ValueError("one mean and one standard error per candidate, at least one candidate")
    if not rms_tolerance >= 1.0:
        raise ValueError(f"rms_tolerance must be at least 1, not {rms_tolerance}")
    best = int(np.nanargmin(mean))
    limit = mean[best] + (standard_error[best] if np.isfinite(standard_error[best]) else 0.0)
    limit = max(limit, rms_tolerance**2 * mean[best])
    return int(np.flatnonzero(mean <= limit)[0])


def next_run_choice(mean: Sequence[float], standard_error: Sequence[float]) -> int:
    """Index of the candidate ``fit`` keeps: the simplest within one standard error or :data:`RMS_TOLERANCE` of
    the best (:func:`one_standard_error_choice`)."""
    return one_standard_error_choice(mean, standard_error, rms_tolerance=RMS_TOLERANCE)


def pooled_error(sse: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each candidate's pooled mean squared error over the folds and its standard error.

    ``sse[i, k]``: candidate i's sum of squared errors on fold k, of ``counts[k]`` samples. The standard error
    is that of a mean of the folds' mean squared errors weighted by their samples (infinite with one fold).
    """
    sse = np.atleast_2d(np.asarray(sse, dtype=float))
    counts = np.asarray(counts, dtype=float)
    mse = sse / counts[None, :]
    weights = counts / counts.sum()
    pooled = mse @ weights
    if len(counts) < 2:
        return pooled, np.full(len(pooled), np.inf)
    spread = ((mse - pooled[:, None]) ** 2) @ weights
    return pooled, np.sqrt(spread / (len(counts) - 1))


__all__ = ["RMS_TOLERANCE", "next_run_choice", "one_standard_error_choice", "pooled_error"]
