"""Reading a run's table: CSV (comma, semicolon or tab separated), Excel, Parquet, MATLAB, TDMS or JSON by suffix, or a
DataFrame.

A text table is read as it was written (:mod:`groupfit.textlayout`: its
encoding, separator, a preamble, decimal commas, a units row), and a time
column of date-times, text ones included (:mod:`groupfit.timestamps`), as
seconds; a compressed table (``.gz``, ``.bz2``, ``.xz``, a ``.zip`` of one file) is read
as the table it holds. Every problem is one line naming the file: a folder or a device
given as a file, an empty or unreadable file, a column named twice.
"""

from __future__ import annotations

import bz2
import gzip
import lzma
import re
import zipfile
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.clock_changes import CLOCK_SHIFTS, through_clock_changes
from groupfit.errors import InputError, first_line
from groupfit.io import note_read
from groupfit.jsonlog import read_json_log
from groupfit.matfile import read_mat
from groupfit.numbercells import sheet_text_numbers, without_cell_units
from groupfit.tdmsfile import read_tdms
from groupfit.textencoding import looks_binary
from groupfit.textlayout import (
    DIGIT,
    RULER,
    SNIFF_LINES,
    WORDS,
    as_numbers,
    layout_of,
    read_text_table,
    without_footer_rows,
    without_units_row,
)
from groupfit.timestamps import is_text, text_clock

TABLE_SUFFIXES = {
    ".csv": "CSV",
    ".txt": "CSV",
    ".xlsx": "Excel",
    ".xlsm": "Excel",
    ".xls": "Excel",
    ".ods": "OpenDocument",
    ".parquet": "Parquet",
    ".mat": "MATLAB",
    ".tdms": "TDMS",
    ".json": "JSON",
    ".jsonl": "JSON",
    ".ndjson": "JSON",
}
"""File types a run is read from, by suffix (anything else is read as CSV)."""
WORKBOOK_SIGNATURES = (b"PK\x03\x04", b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1")
"""How a workbook's bytes begin (a zip: .xlsx, .ods; an OLE compound file: .xls). A file named as a workbook
that begins otherwise is a text table a program saved under a workbook's name, and is read as one."""
PACKAGE_PROMPT = re.compile(r"install the (\S+) package|optional dependency '([^']+)'")
COMPRESSED = {".gz": gzip.decompress, ".bz2": bz2.decompress, ".xz": lzma.decompress, ".zip": None}
"""A text table compressed by a logger or for mail (``log.csv.gz``, a zip of one table), by suffix."""


def read_table(
    source: str | Path | pd.DataFrame, name: str | None = None, encoding: str | None = None
) -> tuple[pd.DataFrame, str, str]:
    """Read a run's table (CSV, Excel, Parquet, MATLAB, TDMS or JSON, by suffix) or take a DataFrame: ``(frame, name,
    label)``.

    ``label`` names the source in error messages. An Excel workbook is read
    from its sheet with the largest table of numbers (a cover sheet is passed
    over, and the label names the sheet), its header found as in a text table
    (a title or a preamble above it is passed over). ``encoding``: a text table's or JSON log's, when
    detection is not to decide (``--encoding``).
    """
    if isinstance(source, pd.DataFrame):
        label = name or "DataFrame"
        _check_unique_columns(list(source.columns), label)
        return source.reset_index(drop=True), (name or "data"), label
    path = Path(source)
    label = str(path)
    _refuse_unreadable(path, label)
    note_read(path)
    compressed = path.suffix.lower() in COMPRESSED
    stem = Path(path.stem).stem if compressed else path.stem
    kind = TABLE_SUFFIXES.get((Path(path.stem) if compressed else path).suffix.lower(), "CSV")
    kind = "CSV" if compressed and kind != "JSON" else kind  # a compressed text table or JSON log
    header = None
    try:
        if kind in ("Excel", "OpenDocument") and not _begins_as_workbook(path):
            frame, header = _text_under_a_workbooks_name(path, kind, label, encoding)
        elif kind == "CSV":
            frame, header = read_text_table(_text_content(path, label, compressed=compressed), encoding)
        elif kind == "MATLAB":
            frame = read_mat(path, label)
        elif kind == "TDMS":
            frame = read_tdms(path, label)
        elif kind == "JSON":
            frame = read_json_log(_text_content(path, label, compressed=compressed), label, encoding)
        elif kind in ("Excel", "OpenDocument"):
            sheet, frame, first, header = _data_sheet(path)
            label = label if first else f"{label} (sheet '{sheet}')"
        else:
            frame, header = _read_parquet(path), _parquet_header(path)
    except InputError:
        raise
    except pd.errors.EmptyDataError:
        raise InputError(f"{label}: the file is empty; a header line and one row per sample are needed") from None
    except ImportError as exc:
        raise InputError(
            f"{label}: reading {kind} files needs the package '{_missing_package(exc)}'; pip install it, or save "
            "the table as .xlsx or CSV"
        ) from None
    except (
        pd.errors.ParserError,
        UnicodeDecodeError,
        LookupError,
        ValueError,
        OSError,
        EOFError,
        zipfile.BadZipFile,
        lzma.LZMAError,
    ) as exc:
        raise InputError(f"{label}: not a readable {kind} table ({first_line(exc)})") from None
    if frame.shape[0] == 0:
        raise InputError(f"{label}: the table has a header but no rows")
    if header is None or len(header) != frame.shape[1]:
        header = list(frame.columns)
    _check_unique_columns(header, label)
    frame.columns = [str(c).strip() for c in frame.columns]
    return frame, (name or stem), label


def _refuse_unreadable(path: Path, label: str) -> None:
    """One line for a path that is no data file groupfit reads: a folder, a device, nothing."""
    if path.is_dir():
        raise InputError(f"{label}: is a folder; give a data file (CSV, Excel, Parquet, MATLAB, TDMS or JSON)")
    if path.exists() and not path.is_file():
        raise InputError(f"{label}: not a regular file (a device or a pipe); give a data file")
    if not path.is_file():
        raise InputError(f"{label}: data file not found; check its path")


def _text_under_a_workbooks_name(
    path: Path, kind: str, label: str, encoding: str | None = None
) -> tuple[pd.DataFrame, list[str]]:
    """A file named as a workbook whose bytes are not one, read as the text table a program saved under that
    name (a web export's tab-separated "Excel" file); refused as no readable workbook when it holds no table
    of numbers."""
    refusal = InputError(
        f"{label}: not a readable {kind} table (its bytes begin as no workbook does, and they are no text table "
        "of numbers either); open it in the program that wrote it and save it as .xlsx or CSV"
    )
    try:
        frame, header = read_text_table(path.read_bytes(), encoding)
    except (InputError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError, ValueError):
        raise refusal from None
    numeric = frame.apply(lambda column: pd.to_numeric(column, errors="coerce")).notna().to_numpy()
    if frame.shape[0] == 0 or frame.shape[1] < 2 or numeric.mean(axis=0).max() < 0.5:
        raise refusal
    return frame, header


def _begins_as_workbook(path: Path) -> bool:
    with path.open("rb") as file:
        start = file.read(8)
    return any(start.startswith(signature) for signature in WORKBOOK_SIGNATURES) or not start


def _missing_package(exc: ImportError) -> str:
    """The package pandas asks for to read a workbook (its name as pip knows it)."""
    if exc.name:
        return {"odf": "odfpy"}.get(exc.name, exc.name)
    found = PACKAGE_PROMPT.search(str(exc))
    return next((name for name in found.groups() if name), "") if found else str(exc)


def without_repeated_headers(frame: pd.DataFrame, label: str, decimal: str = ".") -> tuple[pd.DataFrame, str | None]:
    """The table without rows that repeat its header (a logger that started again and appended to the file),
    its columns of numbers read as numbers again, and a note naming the rows (None: there were none)."""
    needed = max(2, len(frame.columns) // 2)
    texts = [c for c in frame.columns if not pd.api.types.is_numeric_dtype(frame[c])]
    if frame.empty or len(texts) < needed:  # a header row makes every column it crosses one of text
        return frame, None
    matches = np.zeros(len(frame), dtype=int)
    for column in texts:
        matches += (frame[column].astype(str).str.strip() == str(column).strip()).to_numpy(dtype=int)
    repeated = matches >= needed
    if not repeated.any():
        return frame, None
    kept, note = _left_out(frame, repeated, label, "repeating the header", "the logger started again and appended")
    return _numbers_again(kept, decimal, label), note


def without_message_rows(frame: pd.DataFrame, label: str, decimal: str = ".") -> tuple[pd.DataFrame, str | None]:
    """The table without a logger's message lines, its columns of numbers read as numbers again (in the
    table's ``decimal`` mark), and a note naming the rows (None: there were none).

    A message line fills fewer than half the columns, each filled cell with words without a digit
    (``Logging paused``, split at the spaces of a ``.dat``) or a ruler (``-----``). A row holding a digit
    (``Paused at 12:00``, a time stamp without readings), nothing legible (a line of NUL bytes from a
    logger's power loss) or words in most columns (another header) is kept, to be refused.
    """
    texts = [c for c in frame.columns if not pd.api.types.is_numeric_dtype(frame[c])]
    if frame.empty or not texts:
        return frame, None
    filled = np.zeros(len(frame), dtype=int)
    for column in frame.columns:
        filled += ~empty_cells(frame[column])
    worded = np.zeros(len(frame), dtype=int)
    message = pd.Series("", index=frame.index, dtype="string")
    for column in texts:
        cells = frame[column].astype("string").str.strip()
        written = cells.str.contains(WORDS.pattern, regex=True) | cells.str.fullmatch(RULER.pattern)  # not NULs
        words = (written & ~cells.str.contains(DIGIT.pattern, regex=True)).fillna(False).to_numpy(bool)
        worded += words
        message = message.mask(words, (message + " " + cells).str.strip())
    rows = (filled > 0) & (worded == filled) & (2 * filled < len(frame.columns))
    if not rows.any():
        return frame, None
    why = f"a logger's message, such as {message[rows].iloc[0]!r}"
    kept, note = _left_out(frame, rows, label, "holding a message alone", why)
    return _numbers_again(kept, decimal, label), note


def _numbers_again(frame: pd.DataFrame, decimal: str, label: str) -> pd.DataFrame:
    """The frame with every column whose filled cells are all numbers, written with the table's ``decimal``
    mark (and a unit after each, :func:`~groupfit.numbercells.without_cell_units`), read as numbers (a column
    a stray row had left as text)."""
    for column in frame.columns:
        if pd.api.types.is_numeric_dtype(frame[column]):
            continue
        try:
            values = as_numbers(frame[column], decimal, str(column))
        except ValueError:  # a dotted number in a table of decimal commas: refused later, naming its cell
            values = None
        if values is None:
            numbers = pd.to_numeric(frame[column], errors="coerce")
            values = numbers if numbers.notna().sum() == frame[column].notna().sum() else None
        if values is not None:
            frame[column] = values
    try:
        return without_cell_units(frame, decimal)
    except ValueError as exc:  # units after dotted numbers in a table of decimal commas, refused as on reading
        raise InputError(f"{label}: not a readable CSV table ({exc})") from None


def without_repeated_rows(frame: pd.DataFrame, label: str) -> tuple[pd.DataFrame, str | None]:
    """The table without rows identical in every cell, time stamp included, to the row before (a logger that
    wrote a row twice), and a note naming them (None: there were none). In a log whose stamps are coarser than
    its readings (:func:`_coarse_stamps`), such a row is a reading that did not change: kept."""
    if len(frame) < 2:
        return frame, None
    same = np.ones(len(frame) - 1, dtype=bool)
    for column in frame.columns:
        cells = frame[column]
        now, before = cells.iloc[1:].to_numpy(), cells.iloc[:-1].to_numpy()
        same &= (now == before) | (pd.isna(now) & pd.isna(before))
        if not same.any():
            return frame, None
    if _coarse_stamps(frame, same):
        return frame, None
    return _left_out(frame, np.r_[False, same], label, "identical to the row before", "a row written twice")


COARSE_SHARE = 0.1
"""Share of a log's rows that differ from the row before yet share its stamp, from which its stamps are coarser
than its readings (whole minutes on a 15 s logger) and a row identical to the one before is a reading."""


def _coarse_stamps(frame: pd.DataFrame, same: np.ndarray) -> bool:
    """Whether the log's stamps (its non-decreasing column of the most distinct values) are shared by rows that
    differ in another cell, on at least :data:`COARSE_SHARE` of its rows."""
    stamps, most = None, 2
    for column in frame.columns:
        values = frame[column]
        try:
            rising = bool(values.notna().all() and values.is_monotonic_increasing)
        except TypeError:
            continue
        distinct = values.nunique() if rising else 0
        if distinct > most:
            stamps, most = values.to_numpy(), distinct
    if stamps is None:
        return False
    shared = (stamps[1:] == stamps[:-1]) & ~same
    return bool(shared.sum() >= COARSE_SHARE * len(same))


def empty_cells(cells: pd.Series) -> np.ndarray:
    """Where a column's cells are empty: not a value, or text of nothing but spaces."""
    empty = cells.isna()
    if not pd.api.types.is_numeric_dtype(cells):
        empty |= cells.astype("string").str.strip().eq("").fillna(True)
    return empty.to_numpy(dtype=bool)


def without_blank_rows(frame: pd.DataFrame, label: str) -> tuple[pd.DataFrame, str | None]:
    """The table without the rows empty in every cell (a blank row left in a spreadsheet), and a note naming
    them (None: there were none). Rows after them are numbered without them."""
    blank = np.ones(len(frame), dtype=bool)
    for column in frame.columns:
        blank &= empty_cells(frame[column])
        if not blank.any():
            return frame, None
    if blank.all():
        return frame, None
    return _left_out(frame, blank, label, "empty in every column", "a blank row in a spreadsheet")


def without_stray_rows(frame: pd.DataFrame, label: str) -> tuple[pd.DataFrame, list[str], str]:
    """The table without blank rows, message lines, repeated headers and rows written twice; the notes naming
    them, and what was left out in one phrase (empty: nothing), for a refusal whose row numbers count without
    those rows."""
    notes, phrases = [], []
    decimal = frame.attrs.get("decimal", ".")  # of a text table: columns a stray row left as text use it
    messages, headers = (
        partial(without_message_rows, decimal=decimal),
        partial(without_repeated_headers, decimal=decimal),
    )
    for leave_out in (without_blank_rows, messages, headers, without_repeated_rows):
        frame, note = leave_out(frame, label)
        if note is not None:
            notes.append(note)
            phrases.append(note[len(label) + 2 : note.index(LEFT_OUT_TAIL)])
    return frame, notes, "; ".join(phrases)


LEFT_OUT_TAIL = "; rows after them are numbered without them"
"""How a note on rows left out ends."""


def _left_out(frame: pd.DataFrame, rows: np.ndarray, label: str, what: str, why: str) -> tuple[pd.DataFrame, str]:
    """The table without the flagged ``rows``, and the note naming them (the first five, 1-based)."""
    flagged = np.flatnonzero(rows)
    shown = ", ".join(str(i + 1) for i in flagged[:5]) + (" …" if flagged.size > 5 else "")
    note = f"{label}: {flagged.size} row(s) {what} left out (row {shown}: {why}){LEFT_OUT_TAIL}"
    return frame.loc[~rows].reset_index(drop=True), note


def _decompressed(path: Path) -> bytes:
    """The bytes of a compressed text table (a zip archive must hold exactly one file)."""
    suffix = path.suffix.lower()
    if suffix != ".zip":
        return COMPRESSED[suffix](path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        members = [m for m in archive.infolist() if not m.is_dir()]
        if len(members) != 1:
            listed = ", ".join(m.filename for m in members) or "nothing"
            raise InputError(f"{path}: a zip archive of one table is read; this one holds {listed}: unpack it")
        return archive.read(members[0])


def _sheet_header_line(rows: pd.DataFrame) -> int:
    """The row of a sheet's header, from its cells read without a header, found as in a text table
    (:mod:`groupfit.textlayout`): a title, a blank row or a logger's preamble above it is passed over."""
    if not len(rows):
        return 0
    layout = layout_of(rows.head(SNIFF_LINES).to_csv(index=False, header=False))
    return layout.header_line if layout.sep == "," else 0  # cells, not words, are fields


def _data_sheet(path: Path) -> tuple[str | int, pd.DataFrame, bool, list[str] | None]:
    """The workbook's sheet that holds the largest table of numbers, its frame, whether it is the first, and
    its header as written (pandas renames a repeated ``T1`` to ``T1.1`` on reading; None: an empty sheet).

    A logger's export often opens with a cover sheet (the machine, the operator) or a small table of
    calibration constants beside the log; the sheet with the most numeric cells is the log (the first on a
    tie, and the first when none holds numbers).
    """
    cells = pd.read_excel(path, sheet_name=None, header=None)
    lines = {name: _sheet_header_line(rows) for name, rows in cells.items()}
    first_row = [name for name, line in lines.items() if not line]
    headed = pd.read_excel(path, sheet_name=first_row) if first_row else {}
    sheets = {
        name: sheet_text_numbers(
            without_cell_units(
                without_units_row(
                    without_footer_rows(headed[name] if not line else pd.read_excel(path, sheet_name=name, header=line))
                ),
                ".",
            )
        )
        for name, line in lines.items()
    }
    sizes = [
        int(frame.apply(lambda column: pd.to_numeric(column, errors="coerce")).notna().to_numpy().sum())
        for frame in sheets.values()
    ]
    k = int(np.argmax(sizes)) if max(sizes, default=0) > 0 else 0
    name = list(sheets)[k]
    rows = cells[name]
    header = [str(c) for c in rows.iloc[lines[name]].tolist()] if len(rows) else None
    return name, sheets[name], k == 0, header


def _parquet_header(path: Path) -> list[str] | None:
    """The column names of a Parquet file's schema (a repeated name is refused before pyarrow reads it)."""
    try:
        import pyarrow.parquet

        return list(pyarrow.parquet.read_schema(path).names)
    except (ImportError, OSError, ValueError):
        return None


def _check_unique_columns(header, label: str) -> None:
    """Refuse a header that names a column twice, naming both positions (1-based)."""
    seen: dict[str, int] = {}
    for position, name in enumerate(header, start=1):
        name = str(name).strip()
        if name in seen:
            raise InputError(
                f"{label}: column '{name}' appears twice (columns {seen[name]} and {position}); "
                "rename one so that every column name is unique"
            )
        seen[name] = position


def _text_content(path: Path, label: str, *, compressed: bool) -> bytes:
    """A text table's bytes; binary data (a program's own format) refused in one line."""
    content = _decompressed(path) if compressed else path.read_bytes()
    if looks_binary(content):
        raise InputError(
            f"{label}: binary data, not a text table (a program's own format?); groupfit reads CSV and other "
            "text tables, .xlsx, .xls, .ods, Parquet, MATLAB .mat and TDMS files: export the log as one of them"
        )
    return content


def _read_parquet(path: Path) -> pd.DataFrame:
    header = _parquet_header(path)
    if header is not None:
        _check_unique_columns(header, str(path))
    return pd.read_parquet(path)


CLOCK_ORIGIN = "clock_origin_s"
"""``frame.attrs`` key: the date-time of the first row of a time column read as seconds since that row, in seconds
since 1970 (naive stamps taken as UTC, in the clock of the last row where a local clock changed to or from summer
time), so that a file whose stamps go on from another's can be told."""
CLOCK_NOTES = "clock_notes"
"""``frame.attrs`` key: the note on a local clock's changes to or from summer time read through
(:mod:`groupfit.clock_changes`), empty where there were none."""


def datetimes_to_seconds(frame: pd.DataFrame, column: str, label: str) -> None:
    """A date-time column (a Parquet or Excel time stamp, or text such as ``2026-03-02 08:00:00``) as the
    seconds since its first row, a duration as its seconds, in place; other columns are left as they are.
    The first row's date-time is kept as ``frame.attrs[CLOCK_ORIGIN]``; a local clock's changes to and from
    summer time are read through, with a note in ``frame.attrs[CLOCK_NOTES]`` and where they moved the rows in
    ``frame.attrs[CLOCK_SHIFTS]``."""
    if column not in frame.columns:
        return
    raw = frame[column]
    if pd.api.types.is_datetime64_any_dtype(raw) or pd.api.types.is_timedelta64_dtype(raw):
        missing = np.flatnonzero(raw.isna().to_numpy())
        if missing.size:
            raise InputError(f"{label}: row {missing[0] + 1}, column '{column}' is empty; fix or remove that row")
        dated = pd.api.types.is_datetime64_any_dtype(raw)
        start = raw.iloc[0] if dated else pd.Timedelta(0)
        clock = ((raw - start).dt.total_seconds().to_numpy(dtype=float), start.timestamp() if dated else None)
    else:

        def through(seconds: np.ndarray, origin: float) -> np.ndarray:
            return through_clock_changes(raw, seconds, origin, label, column)[0]

        clock = text_clock(raw, column, label, through) if is_text(raw) else None
    if clock is None:
        return
    seconds, origin = clock
    if origin is not None:
        seconds, origin, note, frame.attrs[CLOCK_SHIFTS] = through_clock_changes(raw, seconds, origin, label, column)
        frame.attrs[CLOCK_ORIGIN] = float(origin)
        frame.attrs[CLOCK_NOTES] = (note,) if note else ()
    frame[column] = seconds


__all__ = [
    "CLOCK_NOTES",
    "CLOCK_ORIGIN",
    "TABLE_SUFFIXES",
    "datetimes_to_seconds",
    "empty_cells",
    "read_table",
    "without_blank_rows",
    "without_message_rows",
    "without_repeated_headers",
    "without_repeated_rows",
    "without_stray_rows",
]
