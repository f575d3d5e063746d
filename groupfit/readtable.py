"""Reading a run's table: CSV, Excel or Parquet by suffix, or a DataFrame, with a header checked for repeats."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from groupfit.errors import InputError

TABLE_SUFFIXES = {
    ".csv": "CSV",
    ".txt": "CSV",
    ".xlsx": "Excel",
    ".xlsm": "Excel",
    ".xls": "Excel",
    ".parquet": "Parquet",
}
"""File types a run is read from, by suffix (anything else is read as CSV)."""


def read_table(source: str | Path | pd.DataFrame, name: str | None = None) -> tuple[pd.DataFrame, str, str]:
    """Read a run's table (CSV, Excel or Parquet, by suffix) or take a DataFrame; return ``(frame, name, label)``.

    ``label`` names the source in error messages. An Excel workbook is read
    from its first sheet, with the first row as the header.
    """
    if isinstance(source, pd.DataFrame):
        label = name or "DataFrame"
        _check_unique_columns(list(source.columns), label)
        return source.reset_index(drop=True), (name or "data"), label
    path = Path(source)
    label = str(path)
    if not path.is_file():
        raise InputError(f"{label}: data file not found; check the path given to --data")
    kind = TABLE_SUFFIXES.get(path.suffix.lower(), "CSV")
    try:
        frame = _read_by_kind(path, kind)
    except pd.errors.EmptyDataError:
        raise InputError(f"{label}: the file is empty; a header line and one row per sample are needed") from None
    except ImportError as exc:
        raise InputError(f"{label}: reading {kind} files needs the package '{exc.name}'; pip install it") from None
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError, OSError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{label}: not a readable {kind} table ({first})") from None
    if frame.shape[0] == 0:
        raise InputError(f"{label}: the table has a header but no rows")
    header = _raw_header(path, kind) if kind != "Parquet" else list(frame.columns)
    if header is None or len(header) != frame.shape[1]:
        header = list(frame.columns)
    _check_unique_columns(header, label)
    frame.columns = [str(c).strip() for c in frame.columns]
    return frame, (name or path.stem), label


def _raw_header(path: Path, kind: str) -> list[str] | None:
    """The header as written in the file (pandas renames a repeated ``T1`` to ``T1.1`` on reading)."""
    try:
        if kind == "Excel":
            return [str(c) for c in pd.read_excel(path, sheet_name=0, header=None, nrows=1).iloc[0].tolist()]
        return [str(c) for c in pd.read_csv(path, header=None, nrows=1, skipinitialspace=True, dtype=str).iloc[0]]
    except (ValueError, OSError, IndexError, pd.errors.ParserError, UnicodeDecodeError):
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


def _read_by_kind(path: Path, kind: str) -> pd.DataFrame:
    if kind == "Excel":
        return pd.read_excel(path, sheet_name=0)
    if kind == "Parquet":
        return pd.read_parquet(path)
    return pd.read_csv(path, skipinitialspace=True)
