"""How a text table is laid out, found from its first lines: encoding, separator, header line, decimal mark.

Loggers and controllers write their tables in several ways, and a user
should not have to rewrite one before groupfit reads it:

* the encoding: UTF-16 or UTF-32 when a byte-order mark says so (a
  spreadsheet's "Unicode text" export), else UTF-8 (with or without a
  byte-order mark), else Windows-1252 (a ``°C`` written by a Windows
  program), else Latin-1;
* line ends: ``\r\n`` and a lone ``\r`` (Excel for Mac's "CSV (Macintosh)")
  are read as ``\n``;
* the table's body: the longest run of lines that hold numbers and split into
  as many fields (two or more) at one separator, among the first
  :data:`SNIFF_LINES` lines. The separator is the one (a comma, a semicolon, a
  tab, or runs of spaces for a lab logger's ``.dat``) that gives the longest
  such run, the header's own deciding a tie: a name with a comma in it
  (SINUMERIK's ``T1[u1,1]``) does not make the comma the separator of a
  semicolon table. Runs cut by a line of one field (``Logging paused``), or by a
  message on a row of the table's width (``;Logging paused;;;``), are one body; in
  a table split at spaces, so are first rows with a cell left empty (a sensor that
  began late) under a line of the body's width;
* the header: of the lines of text directly above the body with about as many
  fields (one more or fewer: a separator closing every data row), below the
  last blank one (a spreadsheet's ``;;;;`` row, a ruler ``-----``; in a table
  split at spaces, not double spaced, an empty line too, and lines with a
  value in them are passed over) and but for ``#`` comments, the topmost that
  names the most columns; else the line of text just above the body; a row of
  units right above the body is not the header (:mod:`groupfit.tablehead`).
  Blank rows and rulers between the header and the body are passed over. What
  lies above the header is a preamble and is skipped (a logger's name,
  ``Start;2024-03-04 08:00``, a LabVIEW
  ``***End_of_Header***``, Graphtec's channel list, a TwinCAT Scope or
  SINUMERIK trace head). A text without such a body takes the first line of
  two or more text fields whose next lines have as many;
* the decimal mark: a comma when a data cell is written so (``20,5``), in a
  table whose fields a comma separates when its quoted numbers with a comma
  (``"18,66"``) hold one decimal comma each and no cell has a decimal point;
  ``"1,500"`` alone, which may separate thousands or decimals, is refused there
  naming its column;
* a table aligned in columns by spaces whose rows do not all split into the
  header's names (an empty cell, ``Temp Spindel``, a units row's ``deg C``):
  read by the position of its cells (:mod:`groupfit.fixedwidth`);
* how a cell writes a number (thousands separators, a typeset minus, a unit after it):
  :mod:`groupfit.numbercells`;
* a comment mark before the header's first name (NumPy's ``savetxt``: ``# time_s,T1``), and before a row of
  units right under it, is dropped; a column named ``#`` alone (a HOBO logger's row number) keeps its name
  (:mod:`groupfit.commentmark`);
* a separator at the end of every data row (not of the header) is dropped
  rather than shifting the columns; a column with no name and no value in
  any row (a spreadsheet's trailing ``;;;``) is dropped;
* rows of units or descriptions under the header (``s;°C;°C;µm``): the first
  rows that hold text and no number, above rows that hold numbers, are
  dropped and their columns read as numbers;
* a footer: lines after the last one that holds a number (``Logging stopped
  at 04:00``, ``END``), and rows of statistics under the readings (``Max``,
  ``Min``, ``Avg``: :data:`groupfit.footer.STATISTIC`), are not read; in a sheet, rows
  (:func:`without_footer_rows`).
"""

from __future__ import annotations

import csv
import io
import re
import warnings
from dataclasses import dataclass
from typing import Callable

import pandas as pd

from groupfit.commentmark import without_comment_marks
from groupfit.decimalmark import decimal_mark, quoted_decimal_mark, undecided_commas
from groupfit.fixedwidth import (
    first_uneven_row,
    named_otherwise,
    names_columns,
    read_aligned,
    stands_in_columns,
    uneven_units_row,
)
from groupfit.footer import without_footer, without_footer_rows
from groupfit.numbercells import as_numbers, is_empty_cell, is_number, without_cell_units, without_thousands_separators
from groupfit.spacedtext import with_text_rows_quoted
from groupfit.tablehead import (
    DIGIT,
    RULER,
    below_last_empty_line,
    full_row_above,
    is_padded_title,
    is_units_row,
    message_under_header,
    names_over_numbers,
    naming_most,
    without_numbered_lines,
)
from groupfit.textencoding import decode

DELIMITERS = (",", ";", "\t")
"""Field separators of a text table, tried on its body; a tie goes to the one its header uses most (a comma
on a tie there)."""
WHITESPACE = " "
"""The separator of a table split by runs of spaces (a lab logger's ``.dat``, a fixed-width export)."""
SEPARATORS = (*DELIMITERS, WHITESPACE)
"""Every separator a table's body is tried with, in the order a tie is given."""
SNIFF_LINES = 200
"""Lines looked at for the body, the header and, below it, the decimal mark."""
AGREEING_LINES = 3
"""Lines below a header candidate that must have as many fields as it (a text without a body of numbers)."""
STRAY_ROWS = 2
"""Rows of numbers of another width than the body's (a value more or less) that do not end it."""
WORDS = re.compile(r"[^\W\d_]")


@dataclass(frozen=True)
class TextLayout:
    """Where a text table's header is and how its fields and numbers are written."""

    sep: str
    header_line: int
    """0-based line of the header: the lines before it are a preamble."""
    decimal: str
    undecided: tuple[int, str] | None = None
    """In a table whose fields a comma separates and no number tells its decimal mark: the column (0-based)
    and a quoted cell whose comma may separate thousands or decimals (``"1,500"``); None otherwise."""


@dataclass(frozen=True)
class _Row:
    """A filled line of the sniffed text split at one separator."""

    line: int
    fields: list[str]
    numeric: bool

    @property
    def filled(self) -> int:
        return sum(1 for field in self.fields if field)

    @property
    def blank(self) -> bool:
        """Nothing but separators (a spreadsheet's ``;;;;`` row) or rulers (``-----``, ``=====``)."""
        return all(RULER.fullmatch(field) for field in self.fields if field)

    @property
    def message(self) -> bool:
        """A logger's message on a row of the table's width (``;Logging paused;;;``): fewer than half the fields
        filled, each with words and no digit; no header (:func:`groupfit.readtable.without_message_rows`
        leaves it out)."""
        filled = [field for field in self.fields if field]
        return (
            bool(filled)
            and 2 * len(filled) < len(self.fields)
            and all(WORDS.search(field) and not DIGIT.search(field) for field in filled)
        )

    def short_message(self, width: int) -> bool:
        """A logger's message in a table split at spaces (``Logging paused``): words without digits, fewer than
        half the body's ``width`` of fields."""
        return 2 * len(self.fields) < width and all(WORDS.search(f) and not DIGIT.search(f) for f in self.fields)

    @property
    def is_text(self) -> bool:
        """Two fields or more, not blank, and no number in most of them: a header, units, or a preamble
        line."""
        return len(self.fields) >= 2 and not self.numeric and not self.blank


def header_delimiter(line: str) -> str:
    """The separator a table's header line uses most of (a comma on a tie); runs of spaces when it has none
    of :data:`DELIMITERS` but two words or more."""
    if not any(d in line for d in DELIMITERS) and len(line.split()) > 1:
        return WHITESPACE
    return max(DELIMITERS, key=lambda d: (line.count(d), d == ","))


def fields_of(line: str, sep: str) -> list[str]:
    """A line's fields: split at ``sep``, or at runs of spaces (:data:`WHITESPACE`)."""
    return line.split() if sep == WHITESPACE else line.split(sep)


def with_newlines(text: str) -> str:
    """The text with every line ended by ``\\n``: ``\\r\\n`` (Windows) and a lone ``\\r`` (classic Mac)."""
    return text.replace("\r\n", "\n").replace("\r", "\n") if "\r" in text else text


def layout_of(text: str) -> TextLayout:
    """The layout of a table's text (see the module docstring)."""
    lines = with_newlines(text).split("\n", SNIFF_LINES)[:SNIFF_LINES]
    found = _body_layout(lines)
    if found is None:
        header = _first_agreeing_header(lines)
        sep = header_delimiter(lines[header]) if lines else ","
    else:
        sep, header = found
    below = [line for line in lines[header + 1 :] if line.strip()]
    if sep == ",":
        decimal, undecided = quoted_decimal_mark([[field.strip() for field in _split(line, sep)] for line in below])
        return TextLayout(sep=sep, header_line=header, decimal=decimal, undecided=undecided)
    cells = [field.strip().strip('"') for line in below for field in fields_of(line, sep)]
    return TextLayout(sep=sep, header_line=header, decimal=decimal_mark(cells))


def _rows(lines: list[str], sep: str) -> list[_Row]:
    rows = []
    for k, line in enumerate(lines):
        if line.strip():
            fields = [field.strip().strip('"').strip() for field in _split(line, sep)]
            filled = [field for field in fields if field]
            numbers = sum(1 for field in filled if is_number(field) or is_number(field, ","))
            rows.append(_Row(k, fields, numeric=numbers > 0 and 2 * numbers >= len(filled)))
    return rows


def _split(line: str, sep: str) -> list[str]:
    """A line's fields, a quoted separator kept inside its field."""
    if sep == WHITESPACE:
        return line.split()
    try:
        return next(csv.reader([line], delimiter=sep), [])
    except csv.Error:
        return line.split(sep)


def _numeric_runs(rows: list[_Row]) -> list[tuple[int, int]]:
    """``(first, end)`` positions in ``rows`` of each run of numeric rows of one width (two fields or more)."""
    runs, start = [], None
    for position, row in enumerate([*rows, None]):
        if start is not None and (row is None or not row.numeric or len(row.fields) != len(rows[start].fields)):
            runs.append((start, position))
            start = None
        if start is None and row is not None and row.numeric and len(row.fields) >= 2:
            start = position
    return runs


def _body_layout(lines: list[str]) -> tuple[str, int] | None:
    """The separator whose body of numbers is the longest, and the header line above that body; None when no
    line holds numbers."""
    best, best_score = None, (0, False)
    for sep in SEPARATORS:
        rows = _rows(lines, sep)
        runs = _numeric_runs(rows)
        if not runs:
            continue
        first, end = max(runs, key=lambda run: run[1] - run[0])
        above = rows[first - 1] if first > 0 else None
        header_agrees = above is not None and above.is_text and header_delimiter(lines[above.line]) == sep
        score = (end - first, header_agrees)
        if score > best_score:
            best, best_score = (sep, rows, runs, first), score
    if best is None:
        return None
    sep, rows, runs, first = best
    width, spaced = len(rows[first].fields), sep == WHITESPACE
    first = _body_start(rows, runs, first, spaced=spaced)
    body = [lines[row.line] for row in rows[first : first + SNIFF_LINES] if row.numeric]
    fits = None
    if spaced:  # a line of more words than columns names them when they stand under its words, else none
        aligned = stands_in_columns(body)
        fits = (lambda row: names_columns(lines[row.line], body)) if aligned else (lambda row: row.filled == width)
    return sep, _header_above(rows, first, width, spaced=spaced, fits=fits)


def _body_start(rows: list[_Row], runs: list[tuple[int, int]], first: int, *, spaced: bool = False) -> int:
    """The start of the body that holds the run at ``first``: earlier runs of its width belong to it when
    nothing between them could be a header (a ``Logging paused`` line, a message on a row of separators, a cut
    row) but a repeat of a line above them (a header written again after a logger's restart); in a table split
    at spaces (``spaced``), so does a run right above it whose rows have cells left empty (a sensor that began
    late), under a line of the body's width."""
    width = len(rows[first].fields)
    for start, end in reversed([run for run in runs if run[1] <= first]):
        if len(rows[start].fields) != width and end - start <= STRAY_ROWS:
            continue  # a row with a value more or less (a note typed into the log): the body goes on above it
        if spaced and end == first and len(rows[start].fields) < width and full_row_above(rows, start, width):
            first = start
            continue
        seen_above = {tuple(row.fields) for row in rows[:start] if row.is_text}
        between = [
            row
            for row in rows[end:first]
            if row.is_text and not row.message and not row.short_message(width) and tuple(row.fields) not in seen_above
        ]
        if len(rows[start].fields) != width or between:
            break
        first = start
    return first


def _header_above(
    rows: list[_Row], first: int, width: int, *, spaced: bool = False, fits: Callable[[_Row], bool] | None = None
) -> int:
    """The header line of the body of ``width`` fields that starts at ``rows[first]`` (see the module
    docstring); ``spaced``: the fields are split at runs of spaces, where a title's words are fields as a
    header's names are; ``fits``: whether a line names the body's columns, one name to each
    (:func:`~groupfit.tablehead.naming_most`)."""
    above, top = _lines_above(rows, first, width, spaced=spaced)
    if above:
        chosen = naming_most(above, width, fits)
    elif top > 0 and rows[top - 1].is_text:
        chosen = rows[top - 1]
    else:
        return rows[first].line
    if first + 1 < len(rows) and is_padded_title(chosen.fields) and names_over_numbers(rows[first], rows[first + 1]):
        return rows[first].line  # a title above a header that names columns by numbers (``Zeit;101;102``)
    return chosen.line


def _lines_above(rows: list[_Row], first: int, width: int, *, spaced: bool) -> tuple[list[_Row], int]:
    """The lines of text right above the body that may be its header, and the position below the lowest line
    that is no row of the body (a row of units, a message and blank rows under the header passed over)."""
    top = first
    while top > 0 and (rows[top - 1].blank or message_under_header(rows, top, width)):
        top -= 1  # a ruler, a blank row or a logger's message between the header and the body
    if top > 1 and rows[top - 2].is_text and is_units_row(rows[top - 1].fields):
        top -= 1  # a row of units under the header, ``deg C`` giving it more fields than the header
    strays = top
    while strays > 0 and top - strays < STRAY_ROWS and rows[strays - 1].numeric:
        strays -= 1  # rows of numbers of another width right under the header: strays of the body
    if strays < top and strays > 0 and rows[strays - 1].is_text:
        top = strays
    position = top
    while position > 0 and rows[position - 1].is_text and abs(len(rows[position - 1].fields) - width) <= 1:
        position -= 1
    above = rows[position:top]
    if spaced and not (first + 1 < len(rows) and rows[first + 1].line - rows[first].line > 1):  # not double spaced
        above = without_numbered_lines(below_last_empty_line(above))
    # a line that begins with ``#`` is a comment; split at commas, ``"#"`` alone names a column (HOBO's row number)
    comments = [row.fields[0].startswith("#") and (spaced or row.fields[0] != "#") for row in above]
    return [row for row, comment in zip(above, comments) if not comment] or above, top


def _first_agreeing_header(lines: list[str]) -> int:
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


def _longer_row(body: str, header: list[str], sep: str) -> str | None:
    """Which row of the body holds more values than the header names columns (None: none does)."""
    for row, line in enumerate(body.split("\n")[1:], start=1):
        values = _split(line, sep)
        if len(values) > len(header):
            return (
                f"row {row} has {len(values)} values but the header names {len(header)} columns "
                f"({line.strip()[:60]!r}); remove the extra values or name every column"
            )
    return None


def read_text_table(content: bytes, encoding: str | None = None) -> tuple[pd.DataFrame, list[str]]:
    """A text table's frame and its header as written (pandas renames a repeated name on reading); ``encoding``:
    the one that wrote it, when detection is not to decide (:func:`groupfit.textencoding.decode`)."""
    text = with_newlines(decode(content, encoding))
    layout = layout_of(text)
    body = without_comment_marks(
        without_footer(_from_line(text, layout.header_line), layout.sep, layout.decimal),
        None if layout.sep == WHITESPACE else layout.sep,
    )
    header_text, *rows = body.split("\n")
    if layout.sep == WHITESPACE and (
        first_uneven_row(header_text, rows) is not None
        or named_otherwise(header_text, rows)
        or (uneven_units_row(header_text, rows) and names_columns(header_text, rows))
    ):
        frame, header = read_aligned(header_text, rows, layout.decimal)
    else:
        frame, header = _read_split(body, layout)
    header = [str(name) for name in header]
    if layout.undecided is not None:
        column, cell = layout.undecided
        raise ValueError(undecided_commas(header[column] if column < len(header) else f"column {column + 1}", cell))
    frame, header = _without_empty_unnamed_columns(frame, header)
    frame = without_thousands_separators(without_units_row(frame, decimal=layout.decimal), layout.decimal)
    frame = without_cell_units(frame, layout.decimal)
    frame.attrs["decimal"] = layout.decimal  # for the columns left as text by a stray row, read when it goes
    return frame, header


def _read_split(body: str, layout: TextLayout) -> tuple[pd.DataFrame, list[str]]:
    """The frame of a table's body (its header line first) split at the layout's separator, and its header
    as written; a row with more values than the header has names refused, naming it."""
    header_text = body.split("\n", 1)[0]
    if layout.sep == WHITESPACE:
        header, sep, body = header_text.split(), r"\s+", with_text_rows_quoted(body)
    else:
        header, sep = next(csv.reader([header_text], delimiter=layout.sep, skipinitialspace=True), []), layout.sep
    with warnings.catch_warnings():
        warnings.simplefilter("error", pd.errors.ParserWarning)
        try:
            frame = pd.read_csv(
                io.StringIO(body),
                sep=sep,
                decimal=layout.decimal,
                skipinitialspace=True,
                index_col=False,
                low_memory=False,  # a column read whole: one type, not a type per chunk, and no warning
            )
        except (pd.errors.ParserWarning, pd.errors.ParserError) as exc:
            longer = _longer_row(body, header, layout.sep)
            if longer is None and isinstance(exc, pd.errors.ParserError):
                raise
            raise ValueError(longer or "a row has more values than the header has names; name every column") from None
    return frame, header


def _from_line(text: str, line: int) -> str:
    start = 0
    for _ in range(line):
        start = text.index("\n", start) + 1
    return text[start:]


def _without_empty_unnamed_columns(frame: pd.DataFrame, header: list[str]) -> tuple[pd.DataFrame, list[str]]:
    """The frame and header without the columns that have no name and no value in any row (a spreadsheet's
    trailing ``;;;``); a column with no name that holds a value is kept (and refused when named twice)."""
    if len(header) != frame.shape[1]:
        return frame, header
    kept = [k for k, name in enumerate(header) if name.strip() or not frame.iloc[:, k].map(is_empty_cell).all()]
    if len(kept) == len(header):
        return frame, header
    return frame.iloc[:, kept], [header[k] for k in kept]


def without_units_row(frame: pd.DataFrame, *, decimal: str = ".") -> pd.DataFrame:
    """The frame without the rows of units or descriptions under its header (its first rows that hold text
    and no number), its columns read as numbers where all of the rest are."""
    text_rows = 0
    while text_rows < len(frame) - 1:
        cells = [str(v).strip() for v in frame.iloc[text_rows] if not is_empty_cell(v)]
        if not cells or any(is_number(cell, decimal) or is_number(cell, ",") for cell in cells):
            break  # a number in the row, a decimal comma's too (or nothing in it): a data row
        text_rows += 1
    if text_rows == 0:
        return frame
    rest = frame.iloc[text_rows:].reset_index(drop=True)
    text_columns = [c for c in rest.columns if not pd.api.types.is_numeric_dtype(rest[c])]
    converted = {column: as_numbers(rest[column], decimal, str(column)) for column in text_columns}
    if all(values is None for values in converted.values()):
        return frame
    for column, values in converted.items():
        if values is not None:
            rest[column] = values
    rest.attrs["text_rows"] = [
        {str(column): str(value).strip() for column, value in frame.iloc[row].items() if not is_empty_cell(value)}
        for row in range(text_rows)
    ]  # a units row among them gives the columns' units (groupfit.units_row)
    return rest


__all__ = [
    "DELIMITERS",
    "TextLayout",
    "as_numbers",
    "decode",
    "header_delimiter",
    "is_number",
    "layout_of",
    "read_text_table",
    "with_newlines",
    "without_footer_rows",
    "without_units_row",
]
