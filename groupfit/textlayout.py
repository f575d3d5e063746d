"""How a text table is laid out, found from its first lines: encoding, separator, header line, decimal mark.

Loggers and controllers write their tables in several ways, and a user
should not have to rewrite one before groupfit reads it:

* the encoding: UTF-16 or UTF-32 when a byte-order mark says so (a
  spreadsheet's "Unicode text" export), else UTF-8 (with or without a
  byte-order mark), else Windows-1252 (a ``°C`` written by a Windows
  program), else Latin-1;
* the separator: a comma, a semicolon or a tab, whichever the header line
  uses most (a comma on a tie); runs of spaces when the header has none of
  them (a lab logger's ``.dat``; a name with a space in it cannot be told
  from two there);
* a preamble: lines before the header (a logger's name, the start date) are
  skipped. The header is the first line of two or more fields, none of them a
  number, whose next lines have as many fields;
* the decimal mark: a comma when the separator is not one and a data cell is
  written so (``20,5``);
* a separator at the end of every data row (not of the header) is dropped
  rather than shifting the columns;
* a units row under the header (``s;°C;°C;µm``): a first row that holds text
  and no number, above rows that hold numbers, is dropped and its columns read
  as numbers;
* a footer: lines after the last one that holds a number (``Logging stopped
  at 04:00``, ``END``) are not read; in a sheet, rows (:func:`without_footer_rows`).
"""

from __future__ import annotations

import codecs
import csv
import io
import re
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

DELIMITERS = (",", ";", "\t")
"""Field separators of a text table, tried on its header line: the most frequent wins (a comma on a tie)."""
WHITESPACE = " "
"""The separator of a table whose header has none of :data:`DELIMITERS`: runs of spaces (a lab logger's
``.dat``, a fixed-width export)."""
ENCODINGS = ("utf-8-sig", "cp1252", "latin-1")
"""Tried in this order; Latin-1 reads any byte."""
BYTE_ORDER_MARKS = (
    (codecs.BOM_UTF32_LE, "utf-32-le"),
    (codecs.BOM_UTF32_BE, "utf-32-be"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
)
"""UTF-32 before UTF-16: the UTF-32 little-endian mark begins with UTF-16's."""
SNIFF_LINES = 60
"""Lines looked at for the header and, below it, for the decimal mark."""
AGREEING_LINES = 3
"""Lines below a header candidate that must have as many fields as it."""
COMMA_NUMBER = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")


@dataclass(frozen=True)
class TextLayout:
    """Where a text table's header is and how its fields and numbers are written."""

    sep: str
    header_line: int
    """0-based line of the header: the lines before it are a preamble."""
    decimal: str


def header_delimiter(line: str) -> str:
    """The separator a table's header line uses most of (a comma on a tie); runs of spaces when it has none
    of :data:`DELIMITERS` but two words or more."""
    if not any(d in line for d in DELIMITERS) and len(line.split()) > 1:
        return WHITESPACE
    return max(DELIMITERS, key=lambda d: (line.count(d), d == ","))


def fields_of(line: str, sep: str) -> list[str]:
    """A line's fields: split at ``sep``, or at runs of spaces (:data:`WHITESPACE`)."""
    return line.split() if sep == WHITESPACE else line.split(sep)


def decode(content: bytes) -> str:
    """The text of a file: in the Unicode form its byte-order mark names, else the first of :data:`ENCODINGS`
    that reads it."""
    for mark, encoding in BYTE_ORDER_MARKS:
        if content.startswith(mark):
            try:
                return content[len(mark) :].decode(encoding)
            except UnicodeDecodeError:
                break
    for encoding in ENCODINGS:
        try:
            return content.decode(encoding)
        except UnicodeDecodeError:
            continue
    raise AssertionError("latin-1 decodes every byte")


def layout_of(text: str) -> TextLayout:
    """The layout of a table's text (see the module docstring)."""
    lines = text.split("\n", SNIFF_LINES)[:SNIFF_LINES]
    lines = [line.rstrip("\r") for line in lines]
    header = _header_line(lines)
    sep = header_delimiter(lines[header]) if lines else ","
    below = [line for line in lines[header + 1 :] if line.strip()]
    decimal = "," if sep != "," and any(_comma_number(f) for line in below for f in fields_of(line, sep)) else "."
    return TextLayout(sep=sep, header_line=header, decimal=decimal)


def _header_line(lines: list[str]) -> int:
    filled = [k for k, line in enumerate(lines) if line.strip()]
    for position, k in enumerate(filled):
        sep = header_delimiter(lines[k])
        names = fields_of(lines[k], sep)
        fields = len(names)
        if fields < 2 or any(is_number(field.strip().strip('"')) for field in names):
            continue  # a header names its columns; a line with a number in it is data or a preamble
        following = filled[position + 1 : position + 1 + AGREEING_LINES]
        if all(len(fields_of(lines[j], sep)) == fields for j in following):
            return k
    return filled[0] if filled else 0


def _comma_number(field: str) -> bool:
    return COMMA_NUMBER.fullmatch(field.strip().strip('"')) is not None


def read_text_table(content: bytes) -> tuple[pd.DataFrame, list[str]]:
    """A text table's frame and its header as written (pandas renames a repeated name on reading)."""
    text = decode(content)
    layout = layout_of(text)
    body = _without_footer(_from_line(text, layout.header_line), layout)
    header_text = body.split("\n", 1)[0].rstrip("\r")
    if layout.sep == WHITESPACE:
        header, sep = header_text.split(), r"\s+"
    else:
        header, sep = next(csv.reader([header_text], delimiter=layout.sep, skipinitialspace=True), []), layout.sep
    with warnings.catch_warnings():
        warnings.simplefilter("error", pd.errors.ParserWarning)
        try:
            frame = pd.read_csv(
                io.StringIO(body), sep=sep, decimal=layout.decimal, skipinitialspace=True, index_col=False
            )
        except pd.errors.ParserWarning:
            raise ValueError("a row has more values than the header has names; name every column") from None
    return without_units_row(frame, decimal=layout.decimal), [str(name) for name in header]


def _from_line(text: str, line: int) -> str:
    start = 0
    for _ in range(line):
        start = text.index("\n", start) + 1
    return text[start:]


def _without_footer(body: str, layout: TextLayout) -> str:
    """The table's lines up to its last one that holds a number: what follows is a footer, not data."""
    lines = body.split("\n")
    for end in range(len(lines), 1, -1):
        fields = fields_of(lines[end - 1].rstrip("\r"), layout.sep)
        if any(is_number(field.strip().strip('"'), layout.decimal) for field in fields):
            return body if end == len(lines) else "\n".join(lines[:end]) + "\n"
    return body


def without_footer_rows(frame: pd.DataFrame) -> pd.DataFrame:
    """A sheet's frame without the rows after its last one that holds a number (a footer), its columns read
    as numbers where the footer alone was text."""
    numeric = frame.apply(lambda column: pd.to_numeric(column, errors="coerce")).notna().any(axis=1).to_numpy()
    if not numeric.any() or numeric[-1]:
        return frame
    kept = frame.iloc[: int(np.flatnonzero(numeric)[-1]) + 1].copy()
    for column in kept.columns:
        if not pd.api.types.is_numeric_dtype(kept[column]):
            values = _as_numbers(kept[column], ".")
            if values is not None:
                kept[column] = values
    return kept


def without_units_row(frame: pd.DataFrame, *, decimal: str = ".") -> pd.DataFrame:
    """The frame without a units row under its header, its columns read as numbers where all of them are."""
    if len(frame) < 2:
        return frame
    first = frame.iloc[0]
    cells = [str(v).strip() for v in first if not _empty(v)]
    if not cells or any(is_number(cell, decimal) for cell in cells):
        return frame  # a number in the first row (or nothing in it): a data row
    rest = frame.iloc[1:].reset_index(drop=True)
    text_columns = [c for c in rest.columns if not pd.api.types.is_numeric_dtype(rest[c])]
    converted = {column: _as_numbers(rest[column], decimal) for column in text_columns}
    if all(values is None for values in converted.values()):
        return frame
    for column, values in converted.items():
        if values is not None:
            rest[column] = values
    return rest


def _empty(value) -> bool:
    return value is None or (isinstance(value, float) and np.isnan(value)) or (str(value).strip() == "")


def is_number(cell: str, decimal: str = ".") -> bool:
    """Whether a cell's text is a number, its decimal mark ``decimal``."""
    text = cell.replace(",", ".") if decimal == "," else cell
    try:
        float(text)
    except ValueError:
        return False
    return True


def _as_numbers(column: pd.Series, decimal: str) -> pd.Series | None:
    """The column as float64 when every filled cell is a number, else None."""
    text = column.astype("string").str.strip()
    if decimal == ",":
        text = text.str.replace(",", ".", regex=False)
    values = pd.to_numeric(text, errors="coerce")
    filled = text.notna() & (text != "")
    if not filled.any() or values[filled].isna().any():
        return None
    return values.astype(float)


__all__ = [
    "DELIMITERS",
    "ENCODINGS",
    "TextLayout",
    "decode",
    "header_delimiter",
    "is_number",
    "layout_of",
    "read_text_table",
    "without_footer_rows",
    "without_units_row",
]
