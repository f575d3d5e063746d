"""A footer under a table's readings: lines after the last one that holds a number (``Logging stopped at 04:00``,
``END``), and rows of statistics (``Max``, ``Min``, ``Avg``: :data:`STATISTIC`), are not read.
"""

from __future__ import annotations

import re

import pandas as pd

from groupfit.numbercells import as_numbers, is_empty_cell, is_number

STATISTIC = re.compile(
    r"(?:max(?:imum)?|min(?:imum)?|avg|average|mean|ave|std(?:\.?\s*dev)?|stdev|sigma|rms|p-p|peak-peak|sum|total|"
    r"count|median|range|mittelwert|mittel|summe|anzahl|std\.?\s*abw|standardabweichung|spanne|streuung|varianz|"
    r"variance|moyenne|écart[-\s]type|promedio|media|desv(?:\.|iación)?(?:\s*est)?)\.?\s*:?",
    re.IGNORECASE,
)
"""The label of a row of statistics a logger writes under its readings (``Max``, ``Min``, ``Avg``, ``P-P``)."""


def without_footer(body: str, sep: str, decimal: str) -> str:
    """The table's lines up to its last one that holds a number and is no row of statistics: what follows is
    a footer (``Logging stopped``, ``Max;25.3;26.1``), not data."""
    lines = body.split("\n")
    for end in range(len(lines), 1, -1):
        fields = [field.strip().strip('"') for field in _fields(lines[end - 1].rstrip("\r"), sep)]
        if any(is_number(field, decimal) for field in fields) and not statistics_row(fields):
            return body if end == len(lines) else "\n".join(lines[:end]) + "\n"
    return body


def statistics_row(cells) -> bool:
    """Whether a row's first filled cell labels it as statistics (:data:`STATISTIC`)."""
    filled = [str(cell).strip() for cell in cells if not is_empty_cell(cell)]
    return bool(filled) and STATISTIC.fullmatch(filled[0]) is not None


def _fields(line: str, sep: str) -> list[str]:
    """A line's fields: split at ``sep``, or at runs of spaces (a table split at spaces, ``sep`` a space)."""
    return line.split() if sep == " " else line.split(sep)


def without_footer_rows(frame: pd.DataFrame) -> pd.DataFrame:
    """A sheet's frame without the rows after its last one that holds a number and is no row of statistics
    (a footer), its columns read as numbers where the footer alone was text."""
    numeric = frame.apply(lambda column: pd.to_numeric(column, errors="coerce")).notna().any(axis=1).to_numpy()
    end = len(frame)
    while end and (not numeric[end - 1] or statistics_row(frame.iloc[end - 1])):  # only the last rows are read
        end -= 1
    if end in (0, len(frame)):
        return frame
    kept = frame.iloc[:end].copy()
    for column in kept.columns:
        if not pd.api.types.is_numeric_dtype(kept[column]):
            values = as_numbers(kept[column], ".", str(column))
            if values is not None:
                kept[column] = values
    return kept


__all__ = ["STATISTIC", "statistics_row", "without_footer", "without_footer_rows"]
