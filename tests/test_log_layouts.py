"""Logger exports read as the table they hold: thousands separators, Mac line ends, the preambles of
BenchLink, LabVIEW, Graphtec and SINUMERIK exports and a padded spreadsheet, a spreadsheet's trailing empty
columns, and rows of units and descriptions under the header. The truth is the frame pandas reads from the
same table written plainly; an ambiguous layout is refused in one line naming the column and the cell."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.readtable import read_table, without_repeated_headers
from groupfit.textlayout import header_delimiter, layout_of, read_text_table

PAPER = Path(__file__).resolve().parents[1] / "datasets" / "paper_cycle.csv"


@pytest.fixture(scope="module")
def cells() -> pd.DataFrame:
    """The paper cycle's cells as written (text), with an error in nm of five figures and a fraction."""
    table = pd.read_csv(PAPER, dtype=str)
    error_nm = pd.read_csv(PAPER)["error_um"] * 1000 + 0.25
    table["error_nm"] = [f"{value:.2f}" for value in error_nm]
    return table


def plain_truth(tmp_path: Path, cells: pd.DataFrame, names: list[str] | None = None) -> pd.DataFrame:
    """What pandas reads from the table written plainly (comma separated, decimal points), renamed."""
    path = tmp_path / "plain.csv"
    cells.to_csv(path, index=False)
    truth = pd.read_csv(path)
    if names is not None:
        truth.columns = names
    return truth


def same_frame(read: pd.DataFrame, truth: pd.DataFrame) -> None:
    assert list(read.columns) == list(truth.columns)
    assert len(read) == len(truth)
    for column in truth.columns:
        np.testing.assert_allclose(read[column].to_numpy(float), truth[column].to_numpy(float), rtol=1e-12, atol=1e-12)


def decimal_comma(cell: str, *, thousands: bool = False) -> str:
    """A cell written with a decimal comma, its thousands separated by dots when asked (``1.370,25``)."""
    sign, digits = ("-", cell[1:]) if cell.startswith("-") else ("", cell)
    whole, _, fraction = digits.partition(".")
    if thousands:
        whole = f"{int(whole):,}".replace(",", ".")
    return sign + whole + ("," + fraction if fraction else "")


def comma_thousands(cell: str) -> str:
    whole, _, fraction = cell.partition(".")
    return f"{int(whole):,}" + ("." + fraction if fraction else "")


def lines_of(cells: pd.DataFrame, sep: str, write=lambda column, cell: cell, names=None) -> list[str]:
    header = sep.join(names or cells.columns)
    return [header] + [sep.join(write(column, row[column]) for column in cells.columns) for _, row in cells.iterrows()]


def write(path: Path, lines: list[str], end: str = "\n", encoding: str = "utf-8") -> Path:
    path.write_bytes((end.join(lines) + end).encode(encoding))
    return path


def read(path: Path) -> pd.DataFrame:
    return read_table(path)[0]


def refusal(path: Path, tmp_path: Path, capsys) -> str:
    """The one line ``groupfit fit`` refuses the table with (its exit status 2)."""
    assert main(["fit", "--data", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1
    return lines[0]


# thousands separators


@pytest.mark.parametrize("thousands", [["speed_rpm"], ["error_nm"], ["speed_rpm", "error_nm", "time_s"]])
def test_dots_between_thousands_in_a_decimal_comma_table_are_read_without_them(tmp_path, cells, thousands):
    lines = lines_of(cells, ";", lambda column, cell: decimal_comma(cell, thousands=column in thousands))
    assert any(re.search(r";2\.000;", line) for line in lines) or "speed_rpm" not in thousands
    assert any(re.search(r"1\.\d{3},\d", line) for line in lines) or "error_nm" not in thousands
    same_frame(read(write(tmp_path / "de.csv", lines)), plain_truth(tmp_path, cells))


@pytest.mark.parametrize(
    "column, cell, shown",
    [("T_amb", "20.02", "20.02"), ("speed_rpm", "2000", "20.5")],
    ids=["decimal-point-column", "thousands-and-a-decimal-point"],
)
def test_a_decimal_point_in_a_decimal_comma_table_is_refused_naming_column_and_cell(
    tmp_path, cells, capsys, column, cell, shown
):
    def written(name, value):
        if name != column:
            return decimal_comma(value, thousands=name == "speed_rpm")
        return value if column == "T_amb" else ("20.5" if value == "0" else decimal_comma(value, thousands=True))

    path = write(tmp_path / "mixed.csv", lines_of(cells, ";", written))
    line = refusal(path, tmp_path, capsys)
    assert f"column '{column}' holds '{shown}'" in line
    assert "mixed.csv" in line


def test_a_column_of_three_decimals_after_a_dot_in_a_decimal_comma_table_is_refused(tmp_path, cells, capsys):
    """``10.330`` (a gauge's three decimals pasted into a German sheet) would read as 10330 µm by thousands:
    refused naming the column; a column of thousands whose digits after the dot are all 000 is read."""
    error = (pd.read_csv(PAPER)["error_um"] + 10.0).map(lambda v: f"{v:.3f}")
    gauge = cells.assign(error_um=error).drop(columns="error_nm")
    path = write(tmp_path / "gauge.csv", lines_of(gauge, ";", lambda c, v: v if c == "error_um" else decimal_comma(v)))
    line = refusal(path, tmp_path, capsys)
    assert "column 'error_um' holds only numbers like" in line and "decimal commas" in line
    steady = cells.assign(speed_rpm="2000").drop(columns="error_nm")
    lines = lines_of(steady, ";", lambda c, v: decimal_comma(v, thousands=c == "speed_rpm"))
    assert ";2.000" in lines[1]
    same_frame(read(write(tmp_path / "steady.csv", lines)), plain_truth(tmp_path, steady))


@pytest.mark.parametrize("columns", [["speed_rpm"], ["time_s", "T1", "error_nm"]])
def test_quoted_comma_thousands_in_a_decimal_point_table_are_read_as_numbers(tmp_path, cells, columns):
    def written(column, cell):
        return '"' + (comma_thousands(cell) if column in columns else cell) + '"'

    lines = lines_of(cells, ",", written, names=[f'"{name}"' for name in cells.columns])
    assert any('"2,000"' in line for line in lines) or "speed_rpm" not in columns
    same_frame(read(write(tmp_path / "quoted.csv", lines)), plain_truth(tmp_path, cells))


@pytest.mark.parametrize("sep", [",", ";", "\t"])
def test_a_number_with_three_decimals_in_a_decimal_point_table_is_a_decimal(tmp_path, cells, sep):
    three = cells.assign(error_um=[f"{float(v) / 10 + 1:.3f}" for v in cells["error_um"]])
    lines = lines_of(three, sep)
    assert any(re.search(r"\b1\.\d{3}\b", line) for line in lines)
    path = write(tmp_path / "points.csv", lines)
    assert layout_of(path.read_text()).decimal == "."
    same_frame(read(path), plain_truth(tmp_path, three))


# line ends


@pytest.mark.parametrize("end", ["\r", "\r\n"])
def test_mac_and_windows_line_ends_read_as_the_plain_table(tmp_path, cells, end):
    path = write(tmp_path / "mac.csv", lines_of(cells, ","), end=end)
    same_frame(read(path), plain_truth(tmp_path, cells))


# preambles


def benchlink(cells):
    preamble = ['"Keysight BenchLink Data Logger 3"', '"Name","runA"', '"Comments",""']
    preamble += ['"Acquisition Date","3/2/2026 8:00:00"', '"Total Channels","12"', '"Scan Count","532"', ""]
    return preamble + lines_of(cells, ","), list(cells.columns)


def labview(cells):
    width = len(cells.columns)
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Separator\tTab", "Decimal_Separator\t.", "Date\t2026/03/02"]
    head += ["***End_of_Header***\t", "", "Channels\t" + str(width - 1) + "\t" * (width - 1)]
    head += ["Samples" + "\t532" * (width - 1) + "\t", "Delta_X" + "\t100.000000" * (width - 1) + "\t"]
    head += ["***End_of_Header***" + "\t" * width]
    names = ["X_Value", *cells.columns[1:]]
    body = lines_of(cells, "\t", names=[*names, "Comment"])
    return head + [body[0]] + [line + "\t" for line in body[1:]], [*names, "Comment"]


def graphtec(cells):
    head = ['"Model","GL240"', '"Sampling Interval","100s"', "", '"CH","Signal name","Input","Range"']
    head += ['"CH1","T1","TC_K","100C"', '"CH2","T2","TC_K","100C"', "", '"Logic-Alarm"', ""]
    names = ["No.", *[f"CH{k}" for k in range(1, len(cells.columns))]]
    units = ",".join(["", *["degC"] * 7, "um", "rpm", "", "nm"])
    body = lines_of(cells, ",", names=names)
    return head + [body[0], units] + body[1:], names


def sinumerik(cells):
    names = ["Time [s]", *[f"/Nck/AnalogInput/{c}[u1,{k}] [°C]" for k, c in enumerate(cells.columns[1:8], 1)]]
    names += [f"/Channel/{c}[u1,{k}]" for k, c in enumerate(cells.columns[8:], 1)]
    head = ["Trace;Sinumerik 840D sl;", "Recorded;2026-03-02 08:00:00;", ""]
    return head + lines_of(cells, ";", names=names), names


def padded_spreadsheet(cells):
    pad = ";" * (len(cells.columns) - 1)
    head = [f"Messung;Spindel Warmlauf{pad[1:]}", f"Datum;02.03.2026{pad[1:]}", f"Bediener;Müller{pad[1:]}", pad]
    return head + lines_of(cells, ";", lambda column, cell: decimal_comma(cell)), list(cells.columns)


@pytest.mark.parametrize("layout", [benchlink, labview, graphtec, sinumerik, padded_spreadsheet])
def test_a_loggers_preamble_is_passed_over(tmp_path, cells, layout):
    lines, names = layout(cells)
    path = write(tmp_path / "logger.csv", lines, end="\r\n", encoding="cp1252")
    frame, header = read_text_table(path.read_bytes())
    truth = plain_truth(tmp_path, cells.assign(Comment="") if "Comment" in names else cells, names)
    assert header == names
    same_frame(frame.drop(columns=["Comment"], errors="ignore"), truth.drop(columns=["Comment"], errors="ignore"))
    assert frame.get("Comment", pd.Series(dtype=float)).isna().all()


def test_a_header_with_commas_in_its_names_takes_the_separator_of_its_rows(tmp_path, cells):
    lines, names = sinumerik(cells)
    assert header_delimiter(lines[3]) == ","  # the header alone ties, and a tie goes to the comma
    assert layout_of("\n".join(lines)).sep == ";"


def test_a_header_repeated_inside_the_first_lines_does_not_become_the_header_and_is_left_out(tmp_path, cells):
    lines = lines_of(cells, ",")
    lines.insert(21, lines[0])  # the logger wrote its header again as row 21
    path = write(tmp_path / "repeated.csv", lines)
    assert layout_of(path.read_text()).header_line == 0
    frame, label = read(path), str(path)
    kept, note = without_repeated_headers(frame, label)
    same_frame(kept, plain_truth(tmp_path, cells))
    assert note.startswith(f"{label}: 1 row(s) repeating the header left out (row 21:")


def test_repeated_time_columns_of_a_scope_export_are_refused_by_name(tmp_path, cells, capsys):
    pairs = [name for column in cells.columns[1:4] for name in ("Time", column)]
    rows = [
        "\t".join(cell for column in cells.columns[1:4] for cell in (row["time_s"], row[column]))
        for _, row in cells.iterrows()
    ]
    head = ["Name\tScopeProject", "StartTime\t134176000000000000", ""]
    path = write(tmp_path / "scope.csv", head + ["\t".join(pairs), *rows])
    assert "column 'Time' appears twice (columns 1 and 3)" in refusal(path, tmp_path, capsys)


# empty columns and header rows


def test_a_spreadsheets_trailing_empty_columns_are_dropped(tmp_path, cells):
    lines = [line + ";;" for line in lines_of(cells, ";", lambda column, cell: decimal_comma(cell))]
    path = write(tmp_path / "excel.csv", lines, end="\r\n", encoding="utf-8-sig")
    frame, header = read_text_table(path.read_bytes())
    assert header == list(cells.columns)
    same_frame(frame, plain_truth(tmp_path, cells))


def test_an_unnamed_column_that_holds_a_value_is_still_refused_when_named_twice(tmp_path, cells, capsys):
    lines = lines_of(cells, ";", lambda column, cell: decimal_comma(cell))
    lines = [line + (";7;8" if k == 5 else ";;") for k, line in enumerate(lines)]  # values in both unnamed
    path = write(tmp_path / "excel.csv", lines)
    line = refusal(path, tmp_path, capsys)
    assert "column '' appears twice" in line


def test_rows_of_units_and_descriptions_under_the_header_are_dropped(tmp_path, cells):
    units = ",".join(["s", *["degC"] * 7, "um", "rpm", "-", "nm"])
    words = ",".join(["elapsed", "front bearing", "rear bearing", "housing", "motor", "nose", "base", "air"])
    words += ",probe Z,setpoint,on/off,probe Z"
    lines = lines_of(cells, ",")
    path = write(tmp_path / "three.csv", [lines[0], units, words, *lines[1:]])
    same_frame(read(path), plain_truth(tmp_path, cells))


def test_a_comment_line_as_wide_as_the_table_is_not_its_header(tmp_path):
    comment = "# position table: 2 nodes, every 500 mm"  # one comma: as many fields as the table
    path = write(tmp_path / "table.csv", [comment, "position_mm,d1", "0,-250", "500,250"])
    assert layout_of(path.read_text()).header_line == 1
    same_frame(read(path), pd.DataFrame({"position_mm": [0.0, 500.0], "d1": [-250.0, 250.0]}))


def test_a_line_of_one_field_inside_the_first_rows_does_not_move_the_header(tmp_path, cells, capsys):
    lines = lines_of(cells, ";", lambda column, cell: decimal_comma(cell))
    lines.insert(11, "Logging paused at 8:15")  # a longer run of rows follows it than precedes it
    path = write(tmp_path / "paused.csv", lines)
    assert layout_of(path.read_text()).header_line == 0
    assert "row 11, column 'time_s': 'Logging paused at 8:15' is not a number" in refusal(path, tmp_path, capsys)


def test_a_tab_separated_table_of_decimal_points_with_grouped_thousands_is_read(tmp_path, cells):
    """A US spreadsheet's text export: ``1,000`` in the integer columns, ``20.15`` in the others."""
    grouped = ("time_s", "speed_rpm")
    lines = lines_of(cells, "\t", lambda column, cell: comma_thousands(cell) if column in grouped else cell)
    assert any("1,000\t" in line for line in lines) and any(re.search(r"\t\d+\.\d+", line) for line in lines)
    same_frame(read(write(tmp_path / "us.txt", lines)), plain_truth(tmp_path, cells))


def test_quoted_decimal_commas_in_a_comma_separated_table_are_read(tmp_path, cells):
    """What pandas' ``to_csv(sep=",", decimal=",")`` and LibreOffice write: ``0,"20,15",…``."""
    path = tmp_path / "quoted.csv"
    plain_truth(tmp_path, cells).to_csv(path, index=False, sep=",", decimal=",")
    assert '"' in path.read_text().splitlines()[1]
    same_frame(read(path), plain_truth(tmp_path, cells))


@pytest.mark.parametrize("rows", [12, None], ids=["short", "whole"])
def test_a_comma_separated_table_of_quoted_decimal_commas_in_every_cell_is_read_whole(tmp_path, cells, rows):
    """Every cell quoted and written with a decimal comma (``"0,00","18,66",…``): no row taken for a units row."""
    table = cells.head(rows) if rows else cells
    lines = lines_of(table, ",", lambda column, cell: '"' + f"{float(cell):.2f}".replace(".", ",") + '"')
    assert lines[1].startswith('"0,00","')
    path = write(tmp_path / "quoted.csv", lines)
    assert layout_of(path.read_text()).decimal == ","
    same_frame(read(path), plain_truth(tmp_path, table))


def test_quoted_numbers_whose_comma_may_separate_thousands_or_decimals_are_refused(tmp_path, capsys):
    """``"1,500"`` in a table with no decimal point and no other comma: 1500 or 1.5, nothing tells."""
    table = pd.DataFrame({"time_s": range(0, 600, 60), "T1": range(20, 30), "speed_rpm": "1,500"})
    table["error_um"] = range(10)
    path = tmp_path / "grouped.csv"
    table.to_csv(path, index=False)
    assert '"1,500"' in path.read_text()
    line = refusal(path, tmp_path, capsys)
    assert "grouped.csv" in line and "column 'speed_rpm' holds quoted numbers such as '1,500'" in line
    assert "save the table with decimal points and no thousands separators" in line
    table.assign(T1=table["T1"] + 0.5).to_csv(path, index=False)  # a decimal point: the commas group thousands
    assert read(path)["speed_rpm"].tolist() == [1500.0] * len(table)
