"""A log whose rows are records of several kinds, each with values of its own: averaged onto one clock.

A machine's JSON log or a web interface's dump writes a record whenever a
source reports: a temperature record every 20 s (``btemp``, ``etemp``), a
probe reading every 2 s (``z``). Read as a table, each kind leaves the
other's cells empty, and no row holds every value. :func:`record_kinds_cycle`
finds such a log and the period of its slowest kind, on which
``--resample`` then averages every kind (what a user would ask for by hand).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

MIN_RECORDS = 4
"""Records a kind needs to count as one (a stray row with other values does not make a log mixed)."""
COVERED_SHARE = 0.95
"""Share of the rows the kinds must cover: the rest are stray records."""


def record_kinds_cycle(frame: pd.DataFrame, time: str, seconds: np.ndarray) -> tuple[str, float] | None:
    """``(what the note says, the slowest kind's period in s)`` of a log of records of several kinds; None when
    its rows are not (one kind, or no kind regular enough to count).

    A kind is the set of numeric columns a row fills; the log is one of several kinds when at least two kinds
    have :data:`MIN_RECORDS` rows or more, share no column, and cover :data:`COVERED_SHARE` of the rows. Each
    kind's period is the median step between its rows.
    """
    values = frame.drop(columns=[time]).apply(pd.to_numeric, errors="coerce")
    filled = values.notna().to_numpy()
    if filled.shape[1] < 2:
        return None
    patterns, rows = np.unique(filled, axis=0, return_inverse=True)
    rows = rows.ravel()
    counts = np.bincount(rows, minlength=len(patterns))
    kinds = [k for k in np.argsort(-counts) if counts[k] >= MIN_RECORDS and patterns[k].any()]
    if len(kinds) < 2 or counts[kinds].sum() < COVERED_SHARE * len(frame):
        return None
    if np.any(patterns[kinds].sum(axis=0) > 1):
        return None
    periods = []
    for k in kinds:
        steps = np.diff(seconds[rows == k])
        if steps.size == 0 or not np.median(steps) > 0:
            return None
        periods.append(float(np.median(steps)))
    slowest = max(periods)
    described = "; ".join(
        f"{_named(values.columns[patterns[k]])} every {period:.3g} s" for k, period in zip(kinds, periods)
    )
    what = (
        f"the rows are records of {len(kinds)} kinds ({described}), no row holds every value: the readings of "
        f"each {slowest:.4g} s averaged into one sample"
    )
    return what, slowest


def _named(columns) -> str:
    names = [str(c) for c in columns]
    return ", ".join(names) if len(names) <= 3 else f"{', '.join(names[:2])} … ({len(names)} values)"


__all__ = ["record_kinds_cycle"]
