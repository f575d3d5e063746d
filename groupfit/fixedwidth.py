"""A table aligned in columns by spaces whose rows do not all split into its header's names: read by position.

A fixed-width export (pandas' ``DataFrame.to_string``, a logger's ``printf("%8.2f")`` report) pads every cell
to its column's width. Split at runs of spaces, a row with an empty cell has a value fewer and the rest of it
moves one column to the left, and a name with a space in it (``Temp Spindel``) counts as two. Such a table
(:func:`first_uneven_row` finds one) is read by the position of its cells instead:

* the columns are the runs of character positions that hold a character in some row with a digit in it, so
  an empty cell leaves its column in place and is read as missing; in those rows, each cell holds one value
  at most;
* each word of the header names the column it stands over; a word over none (``Temp`` of a right-aligned
  ``Temp Spindel`` over narrower numbers) belongs to the name it is joined to by one space;
* a column without a name that is one space from one named column alone is part of that column's cells
  (the date of a right-aligned ``2024-03-04 08:00:00`` under ``stamp``);
* a first column without a name that is filled in every row of numbers (``to_string``'s index) is kept as a
  column without a name, as pandas keeps the index column of a CSV (``Unnamed: 0``);
* a row without a digit (units, a logger's message) is split as its words stand over the columns, else a
  word to a column when it has as many words as the table has columns, else kept whole in the first column;
* any other layout (values that do not stand in columns, a word of the header over two columns, a column
  without a name, two names over one column) is refused, naming the first row whose number of values
  differs from the header's.
"""

from __future__ import annotations

import csv
import io
import re

import numpy as np
import pandas as pd

WORD = re.compile(r"\S+")
DIGIT = re.compile(r"\d")
CHUNK_ROWS = 10_000
"""Rows whose filled positions are found at once (bounds the memory a long log takes)."""

Span = tuple[int, int]
"""A column's character positions in a line: ``(first, end)``, the end excluded."""


def first_uneven_row(header: str, rows: list[str]) -> int | None:
    """The number (1-based, blank lines not counted) of the first row with a digit in it that does not split
    at its spaces into as many values as the header into names; None when every such row does."""
    names = len(header.split())
    filled = [row for row in rows if row.strip()]
    return next(
        (number for number, row in enumerate(filled, start=1) if DIGIT.search(row) and len(row.split()) != names),
        None,
    )


def named_otherwise(header: str, rows: list[str], sample: int = 200) -> bool:
    """Whether the columns the first ``sample`` rows of numbers stand in take other names from the header than
    its words split at spaces (``T2 spindle`` over one column, an unnamed index column in front): a table whose
    rows all split evenly, though its names and columns do not pair up one to one."""
    numbers = [row.expandtabs() for row in rows if row.strip() and DIGIT.search(row)][:sample]
    named = _aligned_columns(header.expandtabs(), numbers) if numbers else None
    return named is not None and named[1] != header.split()


def read_aligned(header: str, rows: list[str], decimal: str) -> tuple[pd.DataFrame, list[str]]:
    """The frame of a table aligned in columns, read by position, and its header's names (``""``: a column
    without a name).

    Parameters
    ----------
    header
        The header line.
    rows
        The lines below it (blank ones are passed over).
    decimal
        The table's decimal mark.

    Raises
    ------
    ValueError
        The columns do not line up under the header's names, naming the first row whose number of values
        differs from the header's.
    """
    header = header.expandtabs()
    filled = [row.expandtabs() for row in rows if row.strip()]
    named = _aligned_columns(header, [row for row in filled if DIGIT.search(row)])
    if named is None:
        raise ValueError(_not_aligned(header, filled))
    spans, names = named
    table = io.StringIO()
    writer = csv.writer(table, delimiter="\t", lineterminator="\n")
    writer.writerow(names)
    writer.writerows(_cells(row, spans) for row in filled)
    table.seek(0)
    frame = pd.read_csv(table, sep="\t", decimal=decimal, index_col=False, low_memory=False)
    return frame, names


def _aligned_columns(header: str, numbers: list[str]) -> tuple[list[Span], list[str]] | None:
    """The columns the rows of ``numbers`` stand in and their names from ``header``; None when a cell holds two
    values or the header's words do not line up over the columns."""
    spans = _filled_runs(numbers)
    return _named_columns(header, spans, numbers) if _one_value_per_cell(numbers, spans) else None


def _not_aligned(header: str, filled: list[str]) -> str:
    row = first_uneven_row(header, filled) or 1
    values, names = len(filled[row - 1].split()), len(header.split())
    text = filled[row - 1].strip()
    shown = text if len(text) <= 60 else text[:57] + "..."
    remedy = "fill the empty cell" if values < names else "remove the extra values or name every column"
    return (
        f"row {row} ({shown!r}) has {values} value(s) where the header ({header.strip()[:60]!r}) names {names} "
        f"column(s) (split at spaces), and the columns do not line up under the header's names; {remedy}, or save "
        "the table as CSV"
    )


def _filled_runs(rows: list[str]) -> list[Span]:
    """The runs of character positions that hold a character in some row."""
    width = max((len(row) for row in rows), default=0)
    filled = np.zeros(width, dtype=bool)
    for start in range(0, len(rows), CHUNK_ROWS):
        chunk = "".join(row.ljust(width) for row in rows[start : start + CHUNK_ROWS])
        codes = np.frombuffer(chunk.encode("utf-32-le"), dtype=np.uint32).reshape(-1, width)
        filled |= (codes != ord(" ")).any(axis=0)
    edges = np.flatnonzero(np.diff(np.r_[0, filled.astype(np.int8), 0]))
    return [(int(first), int(end)) for first, end in zip(edges[::2], edges[1::2], strict=True)]


def _one_value_per_cell(rows: list[str], spans: list[Span]) -> bool:
    """Whether no cell of the rows holds two values (a space inside a cell: values that do not stand in columns,
    each row's values as wide as they are)."""
    return all(len(row[first:end].split()) <= 1 for row in rows for first, end in spans)


def _named_columns(header: str, spans: list[Span], numbers: list[str]) -> tuple[list[Span], list[str]] | None:
    """The columns and their names from the header's words over them; None when they do not line up."""
    placed = _placed_words(header, spans)
    if placed is None:
        return None
    names = []
    for column in range(len(spans)):
        words = [word for word, at in placed if at == column]
        if any(later.start() - earlier.end() != 1 for earlier, later in zip(words, words[1:])):
            return None  # two names over one column
        names.append(header[words[0].start() : words[-1].end()] if words else "")
    spans, names = _with_unnamed_parts_joined(spans, names)
    if not names or not all(names[1:]):
        return None
    if not names[0] and not all(row[slice(*spans[0])].strip() for row in numbers):
        return None  # a first column without a name is an index, filled in every row
    return spans, names


def _placed_words(line: str, spans: list[Span]) -> list[tuple[re.Match, int]] | None:
    """Each word of the line with the column it stands over, a word over none with the column of the word it
    is joined to by one space; None when a word stands over two columns or cannot be placed."""
    words = list(WORD.finditer(line))
    columns: list[int | None] = []
    for word in words:
        over = [k for k, (first, end) in enumerate(spans) if first < word.end() and word.start() < end]
        if len(over) > 1:
            return None
        columns.append(over[0] if over else None)
    joined = [later.start() - earlier.end() == 1 for earlier, later in zip(words, words[1:])]
    while None in columns:
        placed_any = False
        for k in [k for k, column in enumerate(columns) if column is None]:
            sides = {columns[k - 1] if k > 0 and joined[k - 1] else None}
            sides.add(columns[k + 1] if k + 1 < len(columns) and joined[k] else None)
            sides.discard(None)
            if len(sides) > 1:
                return None
            if sides:
                columns[k], placed_any = sides.pop(), True
        if not placed_any:
            return None
    return list(zip(words, columns, strict=True))


def _with_unnamed_parts_joined(spans: list[Span], names: list[str]) -> tuple[list[Span], list[str]]:
    """The columns with each column without a name that is one space from one named neighbour alone joined to
    that neighbour (a cell with a space in it)."""
    spans, names = list(spans), list(names)
    k = 0
    while k < len(spans):
        left = k > 0 and bool(names[k - 1]) and spans[k][0] - spans[k - 1][1] == 1
        right = k + 1 < len(spans) and bool(names[k + 1]) and spans[k + 1][0] - spans[k][1] == 1
        if names[k] or left == right:
            k += 1
            continue
        other = k - 1 if left else k + 1
        first, end = min(spans[k][0], spans[other][0]), max(spans[k][1], spans[other][1])
        spans[min(k, other)], names[min(k, other)] = (first, end), names[other]
        del spans[max(k, other)], names[max(k, other)]
    return spans, names


def _cells(row: str, spans: list[Span]) -> list[str]:
    """A row's cells: its text in each column; a row without a digit as its words stand over the columns, else
    a word to a column when it has as many, else whole in the first column."""
    if DIGIT.search(row):
        return [row[first:end].strip() for first, end in spans]
    placed = _placed_words(row, spans)
    if placed is None:
        words = row.split()
        return words if len(words) == len(spans) else [row.strip()] + [""] * (len(spans) - 1)
    cells = []
    for column in range(len(spans)):
        words = [word for word, at in placed if at == column]
        cells.append(row[words[0].start() : words[-1].end()] if words else "")
    return cells


__all__ = ["first_uneven_row", "read_aligned"]
