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
* a word, or a column without a name, one space from two columns belongs to the one on its left when the
  header's names stand flush left over their columns, to the one on its right when flush right
  (:mod:`groupfit.flushnames`: ``Datum Zeit`` flush left over ``02.03.2026 08:00:00`` names one column);
* a name over no column (``spare``) is a column empty in every row;
* a header whose names do not stand over the columns but split at spaces into as many (names one space
  apart, ``time_s T1 T2 error_um``, over wider columns) names them in order;
* a first column without a name that is filled in every row of numbers (``to_string``'s index) is kept as a
  column without a name, as pandas keeps the index column of a CSV (``Unnamed: 0``);
* a row without a digit (units, a logger's message) is split as its words stand over the columns, else a
  word to a column when it has as many words as the table has columns, else kept whole in the first column;
  a row of units under the header with a unit to a column (``[deg C]`` one unit) that do not stand one over
  each is split a unit to a column;
* any other layout is refused: values that do not stand in columns naming the first row whose number of
  values differs from the header's, a header that does not name their columns (a word over two columns, a
  column without a name, two names over one column, a word one space from two names that stand neither
  flush left nor flush right) naming the name or the column.
"""

from __future__ import annotations

import csv
import io
import re

import numpy as np
import pandas as pd

from groupfit.flushnames import LEFT, RIGHT, flush_side
from groupfit.tablehead import DIGIT, RULER, units_of_row

WORD = re.compile(r"\S+")
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


def uneven_units_row(header: str, rows: list[str]) -> bool:
    """Whether a row of units between the header and the first row with a digit in it, a ruler aside, splits at
    its spaces into another number of values than the header into names only because a unit has a space in it
    (``[deg C]``): as many units as names, kept whole."""
    names = len(header.split())
    for row in rows:
        if DIGIT.search(row):
            return False
        if row.strip() and not RULER.fullmatch(row) and len(row.split()) != names:
            units = units_of_row(row.split())
            return units is not None and len(units) == names
    return False


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
    first_number = next((k for k, row in enumerate(filled) if DIGIT.search(row)), len(filled))
    writer.writerows(_cells(row, spans, under_header=k < first_number) for k, row in enumerate(filled))
    table.seek(0)
    frame = pd.read_csv(table, sep="\t", decimal=decimal, index_col=False, low_memory=False)
    return frame, names


def _aligned_columns(header: str, numbers: list[str]) -> tuple[list[Span], list[str]] | None:
    """The columns the rows of ``numbers`` stand in and their names from ``header``; None when a cell holds two
    values or the header's words do not line up over the columns."""
    spans = _filled_runs(numbers)
    return _named_columns(header, spans, numbers) if _one_value_per_cell(numbers, spans) else None


def _not_aligned(header: str, filled: list[str]) -> str:
    """Why a table aligned by spaces is not read: its values do not stand in columns, naming the first row
    that does not split into the header's names, else its header does not name the columns they stand in."""
    numbers = [row for row in filled if DIGIT.search(row)]
    spans = _filled_runs(numbers)
    if numbers and _one_value_per_cell(numbers, spans):
        return (
            f"the header ({header.strip()[:60]!r}) does not name the {len(spans)} columns the values below it stand "
            f"in, one name over each ({_misplaced_name(header, spans, numbers)}); write each name over its "
            "column's values, two spaces or more from the next, or save the table as CSV"
        )
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


def _misplaced_name(header: str, spans: list[Span], numbers: list[str]) -> str:
    """The first of the header's names that stands over two columns, a column no name stands over, or two names
    over one column, in words."""
    words = list(WORD.finditer(header))
    for word in words:
        over = _over(word, spans)
        if len(over) > 1:
            return f"'{word.group()}' stands over columns {over[0] + 1} and {over[1] + 1}"
    for column, span in enumerate(spans):
        above = [word for word in words if _over(word, [span])]
        if not above:
            value = next(cells for row in numbers if (cells := row[slice(*span)].strip()))
            return f"no name stands over column {column + 1}, of values such as '{value}'"
        parted = next((pair for pair in zip(above, above[1:]) if pair[1].start() - pair[0].end() > 1), None)
        if parted:
            return f"'{parted[0].group()}' and '{parted[1].group()}' stand over column {column + 1}"
    return next(
        (
            f"'{word.group()}' stands over no column, one space from the names on both sides"
            for before, word, after in zip(words, words[1:], words[2:])
            if not _over(word, spans) and word.start() - before.end() == 1 and after.start() - word.end() == 1
        ),
        "a name stands over no column",
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
    """The columns and their names from the header's words over them, else, when the header splits at its
    spaces into as many names as there are columns (names one space apart over wider columns), in their order;
    None when neither."""
    named = _placed_names(header, _with_empty_named_columns(header, spans), numbers)
    if named is None and len(header.split()) == len(spans):
        return spans, header.split()
    return named


def _placed_names(header: str, spans: list[Span], numbers: list[str]) -> tuple[list[Span], list[str]] | None:
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
    extents = _word_extents([word for word, _ in placed], [at for _, at in placed], len(spans))
    spans, names = _with_unnamed_parts_joined(spans, names, flush_side(extents, spans))
    if not names or not all(names[1:]):
        return None
    if not names[0] and not all(row[slice(*spans[0])].strip() for row in numbers):
        return None  # a first column without a name is an index, filled in every row
    return spans, names


def _with_empty_named_columns(header: str, spans: list[Span]) -> list[Span]:
    """The columns and one more for each name of the header over none of them: a column empty in every row of
    numbers. A name is words one space apart; where the names stand flush left (right), a word that begins
    (ends) where a column does begins (ends) one."""
    words = list(WORD.finditer(header))
    side = _flush_side(words, spans)
    names: list[list[re.Match]] = []
    for word in words:
        begins = side == LEFT and any(word.start() == first for first, _ in spans)
        ended = side == RIGHT and bool(names) and any(names[-1][-1].end() == end for _, end in spans)
        if names and word.start() - names[-1][-1].end() == 1 and not begins and not ended:
            names[-1].append(word)
        else:
            names.append([word])
    empty = [(name[0].start(), name[-1].end()) for name in names if not any(_over(word, spans) for word in name)]
    return sorted([*spans, *empty])


def _flush_side(words: list[re.Match], spans: list[Span]) -> int | None:
    """Which way the words that stand over one column each stand (:func:`~groupfit.flushnames.flush_side`)."""
    over = [_over(word, spans) for word in words]
    return flush_side(_word_extents(words, [at[0] if len(at) == 1 else None for at in over], len(spans)), spans)


def _over(word: re.Match, spans: list[Span]) -> list[int]:
    """The columns a word stands over."""
    return [k for k, (first, end) in enumerate(spans) if first < word.end() and word.start() < end]


def _placed_words(line: str, spans: list[Span]) -> list[tuple[re.Match, int]] | None:
    """Each word of the line with the column it stands over, a word over none with the column of the word it
    is joined to by one space (of two such, the one :func:`~groupfit.flushnames.flush_side` tells); None when a
    word stands over two columns or cannot be placed."""
    words = list(WORD.finditer(line))
    columns: list[int | None] = []
    for word in words:
        over = _over(word, spans)
        if len(over) > 1:
            return None
        columns.append(over[0] if over else None)
    side = _flush_side(words, spans)
    joined = [later.start() - earlier.end() == 1 for earlier, later in zip(words, words[1:])]
    while None in columns:
        placed_any = False
        for k in [k for k, column in enumerate(columns) if column is None]:
            sides = {columns[k - 1] if k > 0 and joined[k - 1] else None}
            sides.add(columns[k + 1] if k + 1 < len(columns) and joined[k] else None)
            sides.discard(None)
            if len(sides) > 1 and side is None:
                return None
            if sides:
                columns[k], placed_any = min(sides) if side == LEFT else max(sides), True
        if not placed_any:
            return None
    return list(zip(words, columns, strict=True))


def _word_extents(words: list[re.Match], columns: list[int | None], count: int) -> list[Span | None]:
    """Where the words over each of ``count`` columns stand, from the first's start to the last's end."""
    extents: list[Span | None] = [None] * count
    for word, column in zip(words, columns):
        if column is not None:
            known = extents[column]
            extents[column] = (known[0], word.end()) if known else (word.start(), word.end())
    return extents


def _with_unnamed_parts_joined(spans: list[Span], names: list[str], side: int | None) -> tuple[list[Span], list[str]]:
    """The columns with each column without a name that is one space from one named neighbour alone, or from
    two and the names flush on one ``side``, joined to that neighbour (a cell with a space in it)."""
    spans, names = list(spans), list(names)
    k = 0
    while k < len(spans):
        left = k > 0 and bool(names[k - 1]) and spans[k][0] - spans[k - 1][1] == 1
        right = k + 1 < len(spans) and bool(names[k + 1]) and spans[k + 1][0] - spans[k][1] == 1
        if names[k] or not (left or right) or (left and right and side is None):
            k += 1
            continue
        other = k - 1 if left and (not right or side == LEFT) else k + 1
        first, end = min(spans[k][0], spans[other][0]), max(spans[k][1], spans[other][1])
        spans[min(k, other)], names[min(k, other)] = (first, end), names[other]
        del spans[max(k, other)], names[max(k, other)]
    return spans, names


def _cells(row: str, spans: list[Span], *, under_header: bool = False) -> list[str]:
    """A row's cells: its text in each column; a row without a digit as its words stand over the columns, else
    a word to a column when it has as many, else whole in the first column. A row of units right under the header
    with a unit to a column (``s °C °C µm``, ``[deg C]`` one unit) that do not stand one over each: a unit to a
    column."""
    if DIGIT.search(row):
        return [row[first:end].strip() for first, end in spans]
    placed = _placed_words(row, spans)
    units = units_of_row(row.split()) if under_header else None
    spread = placed is not None and len({at for _, at in placed}) == len(spans)
    if units is not None and len(units) == len(spans) and not spread:
        return units
    if placed is None:
        words = row.split()
        return words if len(words) == len(spans) else [row.strip()] + [""] * (len(spans) - 1)
    cells = []
    for column in range(len(spans)):
        words = [word for word, at in placed if at == column]
        cells.append(row[words[0].start() : words[-1].end()] if words else "")
    return cells


def stands_in_columns(rows: list[str]) -> bool:
    """Whether the values of rows of numbers stand in columns, one value to a cell (not one space apart, each
    row's values as wide as they are)."""
    numbers = [row.expandtabs() for row in rows if row.strip()]
    return bool(numbers) and _one_value_per_cell(numbers, _filled_runs(numbers))


def names_columns(header: str, rows: list[str]) -> bool:
    """Whether the header's names stand over the columns the rows with a digit in them stand in, as
    :func:`read_aligned` reads them."""
    numbers = [row.expandtabs() for row in rows if row.strip() and DIGIT.search(row)]
    return _aligned_columns(header.expandtabs(), numbers) is not None


__all__ = [
    "first_uneven_row",
    "named_otherwise",
    "names_columns",
    "read_aligned",
    "stands_in_columns",
    "uneven_units_row",
]
