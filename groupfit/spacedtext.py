"""Rows of text under the header of a table split at spaces that split into more words than it names columns.

A row of units with a space in a unit (``s deg C deg C um``) or a description (``elapsed spindle nose bed``)
under the header of a table whose values are one space apart (``0 19.98 20.01``), not aligned in columns,
splits at its spaces into more words than the header into names, and cannot be placed by position. Such a row,
above the first row with a digit in it, is written as quoted cells: a unit to a cell when it is a row of units
(``deg C`` one unit; a row short of a unit is placed by :mod:`groupfit.units_row`), else the whole row in the
first column. It is read as a row of text under the header (:func:`groupfit.textlayout.without_units_row`
leaves it out of the data and keeps its units).
"""

from __future__ import annotations

from groupfit.tablehead import DIGIT, units_of_row


def with_text_rows_quoted(body: str) -> str:
    """The body (its header line first) with each row of text above its first row with a digit that splits at
    its spaces into more words than the header into names written as quoted cells, one to a column."""
    lines = body.split("\n")
    names = len(lines[0].split())
    for k in range(1, len(lines)):
        if DIGIT.search(lines[k]):
            break
        words = lines[k].split()
        if len(words) <= names:
            continue
        units = units_of_row(words)
        cells = units if units is not None else [lines[k].strip()] + [""] * (names - 1)
        lines[k] = " ".join('"' + cell.replace('"', '""') + '"' for cell in cells)
    return "\n".join(lines)


__all__ = ["with_text_rows_quoted"]
