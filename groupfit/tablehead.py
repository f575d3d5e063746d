"""Which lines of text above a table's body may be its header: not a row of units, not a preamble line.

:mod:`groupfit.textlayout` takes the header from the lines of text directly above the body that have about
as many fields as its rows. Among them, here:

* a row of units right above the body (``s  °C  °C  µm``, ``[s] [deg C] [deg C] [um]``) is under the header,
  not the header, though a unit with a space in it (``deg C``) gives it more fields than the header
  (:func:`is_units_row`);
* in a table split at spaces, whose rows are not double spaced, where a title's or a logger's words are fields
  as a header's names are (in a table split at commas, semicolons or tabs a title fills one field, and the
  line that names the most columns is the header):

  - an empty line ends the header's lines: what stands above it is a preamble (a title, a logger's name)
    even when it has as many words as the table has columns (:func:`below_last_empty_line`);
  - a line with a value for a field (``Machine DMU 50 Spindle 2``, ``Datum 02.03.2026 Uhrzeit 08:00``) is a
    preamble line, unless it is the line right above the body (:func:`without_numbered_lines`);
  - a line of more words than the body has columns that does not name them one to one (a description,
    ``elapsed spindle nose bed``) gives way to a line above it that does (:func:`naming_most`);
* a logger's message right above the body (``Logging started``) under the header is no header
  (:func:`message_under_header`);
* a title a spreadsheet padded with separators (``Warmlauf Spindel;;;;``) is no header when the body's first row
  names columns over numbers (``Zeit;101;102;103;Fehler``): that row is (:func:`is_padded_title`,
  :func:`names_over_numbers`).
"""

from __future__ import annotations

import re
from typing import Callable, Protocol, Sequence, TypeVar

from groupfit.numbercells import is_number

SPACED_UNIT = re.compile(r"(?<!\S)(deg\.?|°|º)\s+([CFK])(?!\S)", re.IGNORECASE)
"""A unit of temperature written with a space in it (``deg C``, ``° F``)."""
TOKEN = re.compile(r"\[[^\]]*\]|\([^)]*\)|[^\s\[(]+")
"""A word of a line, a bracketed unit (``[deg C]``) kept whole."""
UNIT = re.compile(
    r"(?:[°º]\s?[CFK]?|deg\.?\s?[CFK]?|℃|℉|K|celsius|fahrenheit|kelvin"
    r"|[pnµμuc]?m|mm|micron|microns|мм|мкм"
    r"|[mµμu]?s|secs?|sek|min|h|hrs?|std|d|hh:mm(?::ss)?|dd\.mm\.yyyy|yyyy-mm-dd"
    r"|%|%rh|rpm|[1u]/min|min-1|min\^-1|[mk]?v|m?a|m?bar|k?pa|hz|k?w|n|nm|-+|n/a)?",
    re.IGNORECASE,
)
"""A unit a logger writes in a row under its header (bracketed or not; an empty ``[]`` or ``-`` too)."""
BRACKETS = "[]()"
DIGIT = re.compile(r"\d")
"""A digit: a line with one in it holds readings (or a title with a number), a line without one is text."""
RULER = re.compile(r"[-=_~*+|\s]+")
"""A field of a ruler line (``-----``, ``=====``, ``--+--``) drawn under a header or between blocks."""
WORD = re.compile(r"[^\W\d_]{2,}")
"""Letters that make a field a name (``Zeit``, ``Fehler``)."""
VALUE = re.compile(r"[-+]?\d[\d.,:/-]*")
"""A field that is a value, not a name: a number, a date or a time of day (``12345``, ``2026-03-02``, ``08:00``)."""


class _Line(Protocol):
    line: int
    fields: list[str]


Line = TypeVar("Line", bound=_Line)


class _SplitLine(_Line, Protocol):
    """A filled line split at the table's separator, as :mod:`groupfit.textlayout` sees it."""

    numeric: bool

    @property
    def filled(self) -> int: ...

    @property
    def blank(self) -> bool: ...

    @property
    def is_text(self) -> bool: ...

    def short_message(self, width: int) -> bool: ...


SplitLine = TypeVar("SplitLine", bound=_SplitLine)


def units_of_row(fields: Sequence[str]) -> list[str] | None:
    """The units of a line that holds units alone (``s °C °C µm``, ``[s] [deg C]``; ``-`` or ``[]`` for a column
    without one), two or more, not all of them blanks, as written; None for any other line."""
    text = SPACED_UNIT.sub("\\1\0\\2", " ".join(field for field in fields if field))  # ``deg C`` kept whole
    units = [unit.replace("\0", " ") for unit in TOKEN.findall(text)]
    bare = [unit.strip(BRACKETS).strip() for unit in units]
    if len(units) < 2 or not all(UNIT.fullmatch(unit) for unit in bare):
        return None
    if not any(unit.strip("-") and unit.lower() != "n/a" for unit in bare):
        return None
    return units


def is_units_row(fields: Sequence[str]) -> bool:
    """Whether a line holds units alone (:func:`units_of_row`)."""
    return units_of_row(fields) is not None


def below_last_empty_line(lines: Sequence[Line]) -> list[Line]:
    """The lines after the last empty one between two of them (their ``line`` numbers are not consecutive)."""
    start = 0
    for k in range(1, len(lines)):
        if lines[k].line - lines[k - 1].line > 1:
            start = k
    return list(lines[start:])


def without_numbered_lines(lines: Sequence[Line]) -> list[Line]:
    """The lines none of whose fields is a value (:data:`VALUE`, a number), and the last line, right above the
    body, which is the header when no other line is (a column named by a number, ``4711``, or a date)."""
    named = [
        line for line in lines[:-1] if not any(is_number(field) or VALUE.fullmatch(field) for field in line.fields)
    ]
    return [*named, *lines[-1:]]


def message_under_header(rows: Sequence[_SplitLine], top: int, width: int) -> bool:
    """Whether ``rows[top - 1]`` is a logger's message (``Logging started``: a few words without a digit) under
    a line of text with about ``width`` fields, the header."""
    return (
        top > 1
        and rows[top - 1].short_message(width)
        and rows[top - 2].is_text
        and abs(len(rows[top - 2].fields) - width) <= 1
    )


def full_row_above(rows: Sequence[_SplitLine], start: int, width: int) -> bool:
    """Whether the line above ``rows[start]`` has ``width`` fields: a header naming every column, or a full row
    of values."""
    return start > 0 and len(rows[start - 1].fields) == width and not rows[start - 1].blank


def naming_most(above: Sequence[SplitLine], width: int, fits: Callable[[SplitLine], bool] | None = None) -> SplitLine:
    """The topmost of the lines that names the most columns; when that one has more fields than the body's
    ``width`` and does not name its columns one to one (a description under the header: ``elapsed spindle nose
    bed``), the topmost line that ``fits`` does."""
    most = max(row.filled for row in above)
    chosen = next(row for row in above if row.filled == most)
    if fits is None or most <= width or fits(chosen):
        return chosen
    return next((row for row in above if fits(row)), chosen)


def is_padded_title(fields: Sequence[str]) -> bool:
    """Whether a line is one field among three or more empty ones (a title a spreadsheet padded with separators:
    ``Warmlauf Spindel;;;;``)."""
    return len(fields) >= 3 and sum(1 for field in fields if field) == 1


def names_over_numbers(line: _SplitLine, below: _SplitLine) -> bool:
    """Whether a line holds a name (words, no number) over a number of the line below: a header whose other names
    are numbers (``Zeit;101;102;103;Fehler``), not a row of values."""
    return any(
        WORD.search(name)
        and not is_number(name)
        and not is_number(name, ",")
        and (is_number(cell) or is_number(cell, ","))
        for name, cell in zip(line.fields, below.fields)
    )


__all__ = [
    "RULER",
    "full_row_above",
    "is_padded_title",
    "message_under_header",
    "names_over_numbers",
    "naming_most",
    "below_last_empty_line",
    "is_units_row",
    "units_of_row",
    "without_numbered_lines",
]
