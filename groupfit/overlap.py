"""Two logs of one machine that overlap: the later one's first rows repeat the earlier one's last rows.

Exporting overlapping windows from a logger gives such files. Joined for a fit, the repeated rows count twice;
held out as a "next run", the held-out rows were fitted on. Refused, naming the rows, so that one file drops them.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.data import Run
from groupfit.errors import InputError

MIN_REPEATED_ROWS = 2
"""Fewer repeated rows than this are taken as chance (a steady machine logs the same readings twice)."""


def _rows(run: Run) -> np.ndarray:
    error = run.error if run.error is not None else np.full(run.n_samples, np.nan)
    return np.column_stack([run.temps, error])


def repeated_rows(earlier: Run, later: Run) -> int:
    """How many of ``later``'s first rows repeat ``earlier``'s last rows, inputs and error alike (0: none)."""
    return _repeated(_rows(earlier), _rows(later))


def _repeated(before: np.ndarray, after: np.ndarray) -> int:
    if not len(before) or not len(after) or before.shape[1] != after.shape[1]:
        return 0
    same_first = np.all((before == after[0]) | (np.isnan(before) & np.isnan(after[0])), axis=1)
    for start in np.flatnonzero(same_first):  # the earliest start is the longest overlap
        k = len(before) - int(start)
        if k <= len(after) and np.array_equal(before[start:], after[:k], equal_nan=True):
            return k
    return 0


def _same_samples(a: Run, b: Run, rows_a: np.ndarray, rows_b: np.ndarray) -> bool:
    """Whether two runs hold the same readings in every column (in any column order)."""
    if not np.array_equal(rows_a, rows_b, equal_nan=True) or set(a.frame.columns) != set(b.frame.columns):
        return False
    columns = list(a.frame.columns)
    first = a.frame[columns].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
    second = b.frame[columns].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
    return first.shape == second.shape and bool(np.array_equal(first, second, equal_nan=True))


def refuse_overlapping(runs: Sequence[Run], what: str = "as data") -> None:
    """Refuse runs one of which begins with the last rows of another, in part (each checked against each), and a
    run whose every reading is another's: a copy saved again (other line endings, another layout), which
    :func:`groupfit.io.refuse_repeated` cannot tell by its bytes; held out, it would be scored on itself."""
    rows = [_rows(run) for run in runs]
    for i, earlier in enumerate(runs):
        for j, later in enumerate(runs):
            if i == j or earlier.temp_names != later.temp_names:
                continue
            if i < j and rows[i].shape == rows[j].shape and _same_samples(earlier, later, rows[i], rows[j]):
                raise InputError(
                    f"{later.source}: every reading repeats {earlier.source}, given {what} too (the same run saved "
                    "again): give each run once"
                )
            k = _repeated(rows[i], rows[j])
            if MIN_REPEATED_ROWS <= k < min(earlier.n_samples, later.n_samples):  # whole copies: refuse_repeated
                raise InputError(
                    f"{later.source}: its first {k} rows repeat the last {k} rows of {earlier.source}, given {what} "
                    "too (overlapping exports of one log): drop them from one file, so that no row counts twice"
                )


__all__ = ["MIN_REPEATED_ROWS", "refuse_overlapping", "repeated_rows"]
