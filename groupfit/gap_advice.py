"""What a refusal of a column's missed readings advises: what ``--resample`` bridges, what it does not."""

from __future__ import annotations

import numpy as np

from groupfit.resample import GAP_PERIODS


def missing_advice(nonfinite: np.ndarray, column: str) -> str:
    """What to do about the column's missed readings: interpolation covers short gaps; the longest is named
    when it is longer, and dropped at either end of the run or split at in its middle."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], nonfinite.astype(int), [0]])))
    gaps = list(zip(edges[::2], edges[1::2]))
    first, end = max(gaps, key=lambda gap: gap[1] - gap[0])
    length = int(end - first)
    if length <= GAP_PERIODS:
        return (
            f"repair or drop those rows, or let --resample SECONDS interpolate up to {GAP_PERIODS} missed readings "
            "in a row"
        )
    where = f"rows {first + 1}-{end} miss {length} readings in a row, more than --resample SECONDS interpolates"
    if first == 0 or end == nonfinite.size:
        return f"{where} ({GAP_PERIODS}): drop those rows at the run's {'start' if first == 0 else 'end'}"
    return (
        f"{where} ({GAP_PERIODS}): leave '{column}' out of the inputs (--temps), or split the run there into two "
        "files and give both (--data A B, a global model)"
    )


__all__ = ["missing_advice"]
