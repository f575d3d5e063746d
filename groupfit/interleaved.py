"""Two recordings sorted into one log: rows of two runs on one clock, told from several readings per period.

A log that was two recordings (two days, each with its clock from 0) and was
then sorted by time holds two readings of every period, one of each run.
Averaging them (``--resample``) makes a run that never happened. A logger that
writes several readings per period (a fast logger with a coarse clock, a
probe homed three times a minute) holds several readings per period too, and
averaging them is right. The two are told apart by how the first and the last
reading of a period differ, column by column:

- two recordings differ by the gap between two runs: large against how much a
  period's mean moves from one period to the next, and changing smoothly from
  period to period (the runs drift apart slowly);
- readings of one run differ by noise, which changes at random from period to
  period, or by the drift within a period, which is smaller than the drift
  from one period to the next.

A column votes for two recordings when the median difference exceeds
:data:`GAP_OVER_STEP` times the median step of the period means and the
difference changes from period to period by less than :data:`SMOOTH_SHARE`
of itself (median); the log is two recordings when most value columns that
differ at all vote so, and at least :data:`MIN_COLUMNS` columns differ.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from groupfit.errors import InputError

GAP_OVER_STEP = 3.0
"""How many times the period-to-period step of the means the first-to-last difference must exceed."""
SMOOTH_SHARE = 0.3
"""Largest median change of the first-to-last difference from one period to the next, as a share of it."""
MIN_PERIODS = 20
"""Fewest periods with two or more readings for the test to speak."""
SHARED_SHARE = 0.8
"""Least share of the occupied periods that hold two or more readings."""
MIN_COLUMNS = 2
"""Fewest columns whose readings differ within a period: two runs differ in every sensor, a burst of probe
readings with a systematic offset from touch to touch in the error alone."""


def interleaved_recordings(frame: pd.DataFrame, periods: np.ndarray, *, time: str) -> bool:
    """Whether the rows of ``frame`` are two recordings sorted into one clock (see the module).

    Parameters
    ----------
    frame : DataFrame
        The log, rows in time order.
    periods : ndarray of int
        The period (bin) each row falls into, non-decreasing.
    time : str
        The time column, not tested.
    """
    periods = np.asarray(periods)
    starts = np.flatnonzero(np.r_[True, periods[1:] != periods[:-1]])
    counts = np.diff(np.r_[starts, len(periods)])
    shared = counts >= 2
    if shared.sum() < MIN_PERIODS or shared.mean() < SHARED_SHARE:
        return False
    votes = []
    for column in frame.columns:
        if column == time:
            continue
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
        if np.isfinite(values).sum() < 0.9 * len(values):
            continue
        vote = _column_vote(values, starts, counts, shared)
        if vote is not None:
            votes.append(vote)
    return len(votes) >= MIN_COLUMNS and sum(votes) > len(votes) / 2


def _column_vote(values: np.ndarray, starts: np.ndarray, counts: np.ndarray, shared: np.ndarray) -> bool | None:
    """Whether one column reads as two recordings; None when its readings do not differ within a period."""
    first = values[starts[shared]]
    last = values[starts[shared] + counts[shared] - 1]
    difference = np.abs(last - first)
    difference = difference[np.isfinite(difference)]
    if difference.size < MIN_PERIODS or np.median(difference) == 0.0:
        return None
    means = np.add.reduceat(np.nan_to_num(values), starts) / np.maximum(
        np.add.reduceat(np.isfinite(values).astype(float), starts), 1.0
    )
    step = float(np.median(np.abs(np.diff(means))))
    gap = float(np.median(difference))
    change = float(np.median(np.abs(np.diff(difference))))
    return gap > GAP_OVER_STEP * step and change < SMOOTH_SHARE * gap


def stamp_groups(stamps: np.ndarray) -> np.ndarray | None:
    """The group of rows sharing each time stamp (non-decreasing), None when the stamps go back somewhere."""
    stamps = np.asarray(stamps, dtype=float)
    if np.any(np.diff(stamps) < 0):
        return None
    return np.r_[0, np.cumsum(np.diff(stamps) > 0)]


def refuse_interleaved(frame: pd.DataFrame, groupings: list[np.ndarray | None], *, time: str, label: str) -> None:
    """Raise one line naming the fault when any grouping of the rows shows two recordings (see the module)."""
    if any(g is not None and interleaved_recordings(frame, g, time=time) for g in groupings):
        raise InputError(
            f"{label}: the rows look like two recordings sorted into one clock (column '{time}'): every period "
            "holds two readings that differ like two runs, not like one run's readings; averaging them would "
            "make a run that never happened: split the file into its recordings and give them as runs of their "
            "own (--data a.csv b.csv)"
        )
