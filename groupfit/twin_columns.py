"""Input columns that read the same on every row: one channel logged twice under two names.

Least squares and the ridge cope with such twins (their weight is shared), so
both stay inputs; a note names them, since a logger's export that repeats a
channel usually means a channel was meant to be another sensor.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


def twin_columns(names: Sequence[str], values: np.ndarray) -> list[tuple[str, ...]]:
    """The groups of ``names`` whose columns of ``values`` (rows × columns) are equal on every row (an empty cell
    where the other's is empty too), each in the columns' order; one pass over the columns."""
    seen: dict[bytes, list[str]] = {}
    for name, column in zip(names, np.asarray(values, dtype=float).T):
        key = np.where(np.isnan(column), np.nan, column + 0.0)  # one NaN, and -0.0 read as 0.0, as == reads them
        seen.setdefault(key.tobytes(), []).append(name)
    return [tuple(group) for group in seen.values() if len(group) > 1]


def twin_note(label: str, names: Sequence[str], values: np.ndarray) -> str | None:
    """The note naming the inputs of ``label`` that read alike on every row; None when there are none."""
    twins = twin_columns(names, values)
    if not twins:
        return None
    listed = "; ".join(" = ".join(f"'{name}'" for name in group) for group in twins)
    return (
        f"{label}: input columns that read the same on every row: {listed} (one channel logged twice?); both stay "
        "inputs and share their weight; --temps names the inputs"
    )


__all__ = ["twin_columns", "twin_note"]
