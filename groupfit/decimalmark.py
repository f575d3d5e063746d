"""The decimal mark of a text table, told from the cells under its header.

* In a table whose fields a semicolon, a tab or spaces separate: a comma when a cell is a number written
  with one (``20,5``), unless every such cell separates thousands (``1,000``) and another is written with a
  decimal point (``20.15``): a US table that groups its thousands.
* In a table whose fields a comma separates, a number with a comma in it is quoted (``"18,66"``): a comma
  when every such number holds one comma followed by digits, one of them cannot separate thousands
  (``"18,66"``, ``"1500,00"``, ``"0,15"``) and no cell holds a decimal point; else a point, each column's
  commas then read as :mod:`groupfit.numbercells` reads them (thousands in ``"2,000"`` beside ``20.15``).
  When every such number may separate thousands or decimals alike (``"1,500"``) and no cell holds a decimal
  point, nothing in the table tells which, and the table is refused naming the column
  (:func:`undecided_commas`).
"""

from __future__ import annotations

import re

from groupfit.numbercells import COMMA_THOUSANDS, DOT_THOUSANDS

DECIMAL_POINT = re.compile(r"[+-]?\d*\.\d+(?:[eE][+-]?\d+)?")
COMMA_NUMBER = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")
"""A number with one comma in it, followed by digits (``20,5``, ``1,500``)."""


def decimal_mark(cells: list[str]) -> str:
    """The decimal mark of a table whose fields no comma separates, from its cells (stripped, unquoted)."""
    commas = [cell for cell in cells if COMMA_NUMBER.fullmatch(cell)]
    if not commas:
        return "."
    grouped = all(COMMA_THOUSANDS.fullmatch(cell) for cell in commas)
    pointed = any(DECIMAL_POINT.fullmatch(cell) and not DOT_THOUSANDS.fullmatch(cell) for cell in cells)
    return "." if grouped and pointed else ","


def quoted_decimal_mark(rows: list[list[str]]) -> tuple[str, tuple[int, str] | None]:
    """The decimal mark of a table whose fields a comma separates, from its rows' fields (stripped, quotes
    removed), and what leaves it undecided: the column (0-based) and the first cell whose comma may separate
    thousands or decimals, when no cell tells which (None: a cell does)."""
    cells = [(column, field) for row in rows for column, field in enumerate(row)]
    commas = [(column, field) for column, field in cells if "," in field and _comma_or_thousands(field)]
    if not commas or any(_dotted_number(field) for _, field in cells):
        return ".", None
    if not all(COMMA_THOUSANDS.fullmatch(field) for _, field in commas):  # "18,66" separates no thousands
        return ("," if all(COMMA_NUMBER.fullmatch(field) for _, field in commas) else "."), None
    single = [cell for cell in commas if COMMA_NUMBER.fullmatch(cell[1])]  # "1,500", not "1,500,000"
    return ".", (single[0] if len(single) == len(commas) else None)


def undecided_commas(name: str, cell: str) -> str:
    """Why a table whose column ``name`` holds numbers like ``cell`` (``1,500``) and no number that tells its
    decimal mark is refused, and what to write instead."""
    return (
        f"column '{name}' holds quoted numbers such as '{cell}', whose comma may separate thousands or decimals, "
        "and no number in the table tells which; save the table with decimal points and no thousands "
        "separators, or with semicolons between the fields and decimal commas"
    )


def _comma_or_thousands(field: str) -> bool:
    return COMMA_NUMBER.fullmatch(field) is not None or COMMA_THOUSANDS.fullmatch(field) is not None


def _dotted_number(field: str) -> bool:
    """A number written with a decimal point (``20.15``, ``12,345.6``), not one whose dot may separate
    thousands (``1.370``)."""
    if DECIMAL_POINT.fullmatch(field):
        return not DOT_THOUSANDS.fullmatch(field)
    return "." in field and COMMA_THOUSANDS.fullmatch(field) is not None


__all__ = ["COMMA_NUMBER", "DECIMAL_POINT", "decimal_mark", "quoted_decimal_mark", "undecided_commas"]
