"""What a refusal of a column's missed readings advises: what ``--resample`` bridges, what it does not.

In a table built by ``--resample`` (its ``attrs`` holding :data:`~groupfit.resample.LOG_READINGS`) the
missed readings are counted in the log's own cycles (the periods holding its readings), as ``--resample``
counts them, not in periods: a 60 s log resampled to 20 s whose sensor was silent for 10 minutes missed 9
readings, over 29 periods.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from groupfit.resample import GAP_PERIODS, LOG_READINGS, LOG_ROWS


def log_readings(frame: pd.DataFrame) -> np.ndarray | None:
    """Which rows of a resampled ``frame`` hold readings of the log (one of the log's cycles each, however many
    rows of the log were averaged into it; an empty period none); None when ``frame`` is the log."""
    counts = frame.attrs.get(LOG_READINGS)
    if counts is None or len(counts) != len(frame):
        return None
    return np.asarray(counts, dtype=int) > 0


def log_rows(frame: pd.DataFrame) -> np.ndarray | None:
    """For each row of a resampled ``frame`` and one past its last, the position in the log of the first row
    binned into it or later (:data:`~groupfit.resample.LOG_ROWS`); None when ``frame`` is the log."""
    rows = frame.attrs.get(LOG_ROWS)
    if rows is None or len(rows) != len(frame) + 1:
        return None
    return np.asarray(rows, dtype=int)


def rows_in_log(rows: np.ndarray, first: int, end: int) -> str:
    """The log's rows binned into the resampled rows ``first`` to ``end - 1`` (1-based, as a user counts them);
    between which two they fall when none was."""
    low, high = int(rows[first]), int(rows[end])
    if high == low:
        return f"between the log's rows {low} and {low + 1}"
    return f"the log's row {low + 1}" if high == low + 1 else f"the log's rows {low + 1}-{high}"


def same_rows(rows: np.ndarray | None, first: int, end: int) -> bool:
    """Whether the resampled rows ``first`` to ``end - 1`` are the log's rows of the same numbers, one each (a
    log resampled to its own period), or the table is the log."""
    return rows is None or (
        int(rows[first]) == first and int(rows[end]) == end and bool(np.all(np.diff(rows[first : end + 1]) == 1))
    )


def resampled_row(row: int, rows: np.ndarray | None) -> str:
    """Row ``row`` (0-based) of a table, named in the log as well when the table was resampled."""
    if same_rows(rows, row, row + 1):
        return f"row {row + 1}"
    return f"row {row + 1} of the resampled run ({rows_in_log(rows, row, row + 1)})"


def missing_count(nonfinite: np.ndarray, readings: np.ndarray | None) -> str:
    """How many values the refused column misses: non-finite values of the log, or, resampled, the readings
    of the log it missed and the periods without a value."""
    missed = int(nonfinite.sum() if readings is None else readings[nonfinite].sum())
    if missed == nonfinite.sum():
        return f"{missed} non-finite value(s) in that column"
    return f"{missed} missed reading(s) of the log in that column, {int(nonfinite.sum())} period(s) without a value"


def missing_advice(
    nonfinite: np.ndarray, column: str, readings: np.ndarray | None = None, rows: np.ndarray | None = None
) -> str:
    """What to do about the column's missed readings: interpolation covers short gaps; the longest is named
    when it is longer, and dropped at either end of the run or split at in its middle.

    Parameters
    ----------
    nonfinite : ndarray of bool
        Where the column holds no finite value.
    column : str
        The column's name.
    readings : ndarray of bool, optional
        For a resampled table, which of its rows hold readings of the log (:func:`log_readings`): a gap's
        length is then the readings the log missed in it, not its periods.
    rows : ndarray of int, optional
        For a resampled table, :func:`log_rows`: the gap is named in the log's rows as well.
    """
    edges = np.flatnonzero(np.diff(np.concatenate([[0], nonfinite.astype(int), [0]])))
    gaps = list(zip(edges[::2], edges[1::2]))
    counts = np.ones(nonfinite.size, dtype=int) if readings is None else readings.astype(int)
    first, end = max(gaps, key=lambda gap: (int(counts[gap[0] : gap[1]].sum()), gap[1] - gap[0]))
    length = int(counts[first:end].sum())
    if length <= GAP_PERIODS:
        return (
            f"repair or drop those rows, or let --resample SECONDS interpolate up to {GAP_PERIODS} missed readings "
            "in a row"
        )
    where = f"rows {first + 1}-{end} miss {length} readings in a row"
    if readings is not None and not (rows is not None and same_rows(rows, first, end)):
        log = f" ({rows_in_log(rows, first, end)})" if rows is not None else ""
        periods = f" ({end - first} periods)" if length != end - first else ""
        where = f"rows {first + 1}-{end} of the resampled run{log} miss {length} readings of the log in a row{periods}"
    where += ", more than --resample SECONDS interpolates"
    if first == 0 or end == nonfinite.size:
        return f"{where} ({GAP_PERIODS}): drop those rows at the run's {'start' if first == 0 else 'end'}"
    return (
        f"{where} ({GAP_PERIODS}): leave '{column}' out of the inputs (--temps), or split the run there into two "
        "files and give both (--data A B, a global model)"
    )


__all__ = ["log_readings", "log_rows", "missing_advice", "missing_count", "resampled_row", "rows_in_log", "same_rows"]
