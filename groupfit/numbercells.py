"""How a cell writes a number: its decimal mark, thousands separators, a typeset minus, a unit after it.

A logger or a spreadsheet writes a number in the conventions of its country and its program, and groupfit
reads it as written:

* a decimal comma in a table that does not separate its fields with commas (``20,5``);
* thousands separators: in a table of decimal commas, a column whose dotted numbers all read as ``1.370`` or
  ``12.345,6`` is read without the dots; any other dotted number there (``20.5``) is refused, naming the column
  and the cell. In a table of decimal points, a column whose cells with a comma all read as ``2,000`` or
  ``12,345.6`` is read without the commas; spaces (French, ISO 31-0: ``12 500,5``) and apostrophes (Swiss:
  ``12'500.5``) between the thousands are read in either; a column of a table of decimal points whose cells
  with a comma hold numbers that cannot all separate thousands (``"20,15"``, quoted where commas separate the
  fields) and no decimal point is read with decimal commas;
* the minus sign a typesetting program writes (``−0.5``, U+2212);
* a unit after the number in every cell of a column (``20.5 °C``, ``1.25µm``): read as the column's unit
  (:mod:`groupfit.units_row`).
"""

from __future__ import annotations

import re

import pandas as pd

DOT_THOUSANDS = re.compile(r"[+-]?[1-9]\d{0,2}(?:\.\d{3})+(?:,\d+)?")
"""A number with dots between its thousands (``1.370``, ``12.345,6``): the only dotted number a table of
decimal commas holds."""
COMMA_THOUSANDS = re.compile(r"[+-]?[1-9]\d{0,2}(?:,\d{3})+(?:\.\d+)?")
"""A number with commas between its thousands (``2,000``, ``12,345.6``) in a table of decimal points."""
COMMA_DECIMAL = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")
"""A number written with a decimal comma (``20,15``), quoted in a table whose fields a comma separates."""
GROUP_MARK = re.compile("[ \u00a0\u202f'\u2019]")
SPACED_THOUSANDS = re.compile(r"[+\-\u2212]?[1-9]\d{0,2}(?:[ \u00a0\u202f'\u2019]\d{3})+(?:[.,]\d+)?")
"""A number with spaces (French, ISO 31-0) or apostrophes (Swiss) between its thousands: ``2 000``,
``12 345,6``, ``1'234.5``."""
UNICODE_MINUS = "\u2212"
"""The minus sign a typesetting program writes (``−0.5``), read as ``-``."""


def is_number(cell: str, decimal: str = ".") -> bool:
    """Whether a cell's text is a number, its decimal mark ``decimal``."""
    text = cell.replace(",", ".") if decimal == "," else cell
    try:
        float(text)
    except ValueError:
        return False
    return True


def as_numbers(column: pd.Series, decimal: str, name: str) -> pd.Series | None:
    """The column as float64 when every filled cell is a number (thousands separators read as
    :func:`_plain_numbers` reads them), else None."""
    text = _plain_numbers(column.astype("string").str.strip(), decimal, name)
    values = pd.to_numeric(text, errors="coerce")
    filled = text.notna() & (text != "")
    if not filled.any() or values[filled].isna().any():
        return None
    return values.astype(float)


def without_thousands_separators(frame: pd.DataFrame, decimal: str) -> pd.DataFrame:
    """The frame with its text columns of numbers written with thousands separators read as numbers."""
    changed = {}
    for column in frame.columns:
        if pd.api.types.is_numeric_dtype(frame[column]):
            continue
        text = frame[column].astype("string").str.strip()
        plain = _plain_numbers(text, decimal, str(column), thousands_only=True)
        if plain is not None:
            values = pd.to_numeric(plain, errors="coerce")
            filled = plain.notna() & (plain != "")
            changed[column] = values.astype(float) if values[filled].notna().all() else plain.astype(object)
    return _with_columns(frame, changed)


def _plain_numbers(text: pd.Series, decimal: str, name: str, *, thousands_only: bool = False) -> pd.Series | None:
    """A column's stripped text cells with their numbers written with a decimal point and no thousands
    separators; None when ``thousands_only`` and the column has none.

    Raises
    ------
    ValueError
        A table of decimal commas holds a dotted number that is not one with thousands separators.
    """
    written = text
    spelled = text.map(_without_group_spaces, na_action="ignore").astype("string")  # an empty column: no text
    text = spelled.str.replace(UNICODE_MINUS, "-", regex=False)
    respelled = not text.equals(written)
    cells = [cell for cell in text.dropna().unique() if cell]
    if decimal == ",":
        dotted = [cell for cell in cells if "." in cell and (DOT_THOUSANDS.fullmatch(cell) or is_number(cell))]
        odd = next((cell for cell in dotted if not DOT_THOUSANDS.fullmatch(cell)), None)
        if odd is not None:
            raise ValueError(
                f"column '{name}' holds '{odd}', a decimal point in a table of decimal commas, where a dot "
                "can only separate thousands (1.370); write that column with decimal commas"
            )
        _refuse_either_reading(cells, dotted, name)
        if thousands_only and not dotted and not respelled:
            return None
        rewritten = {cell: cell.replace(".", "") if cell in dotted else cell for cell in cells}
        return text.map(lambda cell: rewritten.get(cell, cell)).str.replace(",", ".", regex=False)
    commas = [cell for cell in cells if "," in cell]
    if commas and not any("." in cell for cell in cells) and all(COMMA_DECIMAL.fullmatch(c) for c in commas):
        if not all(COMMA_THOUSANDS.fullmatch(cell) for cell in commas):  # "20,15" holds no thousands
            return text.str.replace(",", ".", regex=False)
    if not commas or not all(COMMA_THOUSANDS.fullmatch(cell) for cell in commas):
        return None if thousands_only and not respelled else text
    return text.str.replace(",", "", regex=False)


ONE_DOT_GROUP = re.compile(r"[+-]?[1-9]\d{0,2}\.(\d{3})")
"""A number with one dot followed by three digits (``10.330``): thousands or three decimals alike."""


def _refuse_either_reading(cells: list[str], dotted: list[str], name: str) -> None:
    """Refuse a column of a table of decimal commas whose every cell is ``d.ddd`` to ``ddd.ddd`` with other
    digits than ``000`` after the dot: a gauge's three decimals (``10.330`` µm) read as thousands would be
    1000 times too large, and nothing in the column tells the two apart."""
    if not cells or len(dotted) != len(cells):
        return
    groups = [ONE_DOT_GROUP.fullmatch(cell) for cell in cells]
    if all(groups) and any(group.group(1) != "000" for group in groups):
        raise ValueError(
            f"column '{name}' holds only numbers like '{cells[0]}' in a table of decimal commas, whose dot may "
            "separate thousands or three decimals; write that column with decimal commas (or its thousands "
            "without dots)"
        )


COMMA_GROUPS = re.compile(r"[+-]?[1-9]\d{0,2}(?:,\d{3})+")
"""A number whose comma may separate thousands or decimals alike (``1,250``, ``20,013``)."""


def sheet_text_numbers(frame: pd.DataFrame) -> pd.DataFrame:
    """A sheet's frame with its columns of numbers stored as text and written with a comma read as numbers:
    the comma as a thousands separator where a cell of the column holds a decimal point (``1,250.5``), as a
    decimal comma where a cell cannot hold thousands (``20,5``, ``1234,5``).

    Raises
    ------
    ValueError
        A column of numbers whose every comma could be either (``1,250``; ``20,013``), named with a cell.
    """
    read = {}
    for column in frame.columns:
        if pd.api.types.is_numeric_dtype(frame[column]):
            continue
        text = frame[column].astype("string").str.strip()
        cells = [cell for cell in text.dropna().unique() if cell]
        commas = [cell for cell in cells if "," in cell]
        if not commas:
            continue
        if any("." in cell for cell in cells):
            values = as_numbers(text, ".", str(column))
        elif all(COMMA_GROUPS.fullmatch(cell) for cell in commas):
            if as_numbers(text, ".", str(column)) is not None:
                raise ValueError(
                    f"column '{column}' holds numbers as text, such as '{commas[0]}', whose comma may separate "
                    "thousands or decimals; format the column's cells as numbers, or save the sheet as CSV"
                )
            continue
        else:
            values = None
        if values is None:
            try:
                values = as_numbers(text, ",", str(column))
            except ValueError:
                continue
        if values is not None:
            read[column] = values
    return _with_columns(frame, read)


CELL_WITH_UNIT = re.compile(r"([^\s°µμ%\[(a-df-zA-DF-Z]+?)\s*([°µμ%]?[\[(]?[a-zA-Z°µμ%./]+[\])]?)")
"""A number followed by a unit in the same cell (``20.5 °C``, ``1.25µm``, ``12 [mm]``)."""


def without_cell_units(frame: pd.DataFrame, decimal: str) -> pd.DataFrame:
    """The frame with its text columns whose every filled cell is a number and one same unit (``20.5 °C``)
    read as numbers; the units kept as the columns' (``frame.attrs["cell_units"]``, read as a row of units)."""
    read, units = {}, {}
    for column in frame.columns:
        if pd.api.types.is_numeric_dtype(frame[column]):
            continue
        text = frame[column].astype("string").str.strip()
        filled = text.notna() & (text != "")
        found = text.str.extract("^" + CELL_WITH_UNIT.pattern + "$")
        written = found[1][filled]
        if not filled.any() or bool(written.isna().any()) or written.nunique() != 1:
            continue
        values = as_numbers(found[0], decimal, str(column))
        if values is not None:
            read[column], units[str(column)] = values, str(written.iloc[0])
    if not read:
        return frame
    frame = _with_columns(frame, read)
    frame.attrs["cell_units"] = {**frame.attrs.get("cell_units", {}), **units}
    return frame


def _with_columns(frame: pd.DataFrame, columns: dict) -> pd.DataFrame:
    """The frame with ``columns`` (name: values) in place of its own, copied once (the frame itself: none)."""
    if not columns:
        return frame
    frame = frame.copy()
    for column, values in columns.items():
        frame[column] = values
    return frame


def _without_group_spaces(cell: str) -> str:
    """A number with spaces or apostrophes between its thousands (``2 000``, ``12 345,6``, ``1'234.5``) written
    without them; any other cell as it is."""
    return GROUP_MARK.sub("", cell) if SPACED_THOUSANDS.fullmatch(cell) else cell


def is_empty_cell(value) -> bool:
    """Whether a cell as read holds nothing: None, NaN or only spaces."""
    return value is None or (isinstance(value, float) and value != value) or not str(value).strip()


__all__ = [
    "as_numbers",
    "is_empty_cell",
    "is_number",
    "sheet_text_numbers",
    "without_cell_units",
    "without_thousands_separators",
]
