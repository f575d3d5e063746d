"""Space-aligned logs laid out as loggers and people write them: empty lines and a preamble with numbers above
the header, a date and a time of day in two columns or under one name, names one space apart, a row of units
under the header, a column left empty. The truth is the table the test wrote; a layout that cannot be read
one way only is refused in one line naming the file and what to change."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.readtable import read_table

PAPER = Path(__file__).resolve().parents[1] / "datasets" / "paper_cycle.csv"
COLUMNS = ["time_s", "T1", "T2", "T3", "error_um"]
TEMPS = ["T1", "T2", "T3"]
BLANK_ROW, BLANK_COLUMN = 12, "T2"


@pytest.fixture(scope="module")
def log() -> pd.DataFrame:
    """The first 40 rows of the shipped run (readings with two decimals at most)."""
    return pd.read_csv(PAPER)[COLUMNS].head(40).astype(float)


def cell(value, decimals: int = 2) -> str:
    if isinstance(value, str):
        return value
    return "" if np.isnan(value) else f"{value:.{decimals}f}"


def aligned(frame: pd.DataFrame, head_rows=(), *, flush: str = "right", gap: int = 2, decimals: int = 2) -> list[str]:
    """The frame as lines of cells padded to their column's width, ``gap`` spaces apart, flush left or right;
    ``head_rows`` (a row of units) under the header."""
    rows = [list(frame.columns), *[list(row) for row in head_rows]]
    rows += [[cell(value, decimals) for value in row] for row in frame.itertuples(index=False)]
    widths = [max(len(row[k]) for row in rows) for k in range(frame.shape[1])]
    pad = str.rjust if flush == "right" else str.ljust
    return [(" " * gap).join(pad(text, width) for text, width in zip(row, widths)).rstrip() for row in rows]


def write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def with_blank(frame: pd.DataFrame) -> pd.DataFrame:
    blank = frame.copy()
    blank.loc[BLANK_ROW, BLANK_COLUMN] = np.nan
    return blank


def assert_reads_as(path: Path, truth: pd.DataFrame) -> pd.DataFrame:
    """The table read from ``path``, checked to hold the names and every value of ``truth``."""
    read = read_table(path)[0]
    assert list(read.columns) == list(truth.columns)
    for name in truth.columns:
        if pd.api.types.is_numeric_dtype(truth[name]):
            np.testing.assert_array_equal(read[name].to_numpy(float), truth[name].to_numpy(float))
        else:
            assert read[name].tolist() == truth[name].tolist()
    return read


def refusal(path: Path, capsys) -> str:
    """The one line ``fit`` refuses the file with (exit status 2)."""
    assert main(["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--out", str(path.parent / "out")]) == 2
    message = capsys.readouterr().err.strip()
    assert len(message.splitlines()) == 1 and str(path) in message
    return message


@pytest.mark.parametrize("empty_lines", [1, 3, 6])
@pytest.mark.parametrize("blank_cell", [False, True])
def test_a_title_above_empty_lines_is_no_header_though_it_has_as_many_words(tmp_path, log, empty_lines, blank_cell):
    table = with_blank(log) if blank_cell else log
    lines = ["Spindle warm up test run", *[""] * empty_lines, *aligned(table)]
    assert len(lines[0].split()) == len(COLUMNS)
    assert_reads_as(write(tmp_path / "titled.txt", lines), table)


@pytest.mark.parametrize(
    "preamble",
    [
        ["Logger S/N 12345  started 2026-03-02 08:00", "Machine DMU 50 Spindle 2"],
        ["Machine DMU 50 Spindle 2", ""],
        ["Logger 12345 started 08:00 OK"],
        ["Datum 02.03.2026 Uhrzeit 08:00 Ende"],
    ],
)
@pytest.mark.parametrize("blank_cell", [False, True])
def test_a_preamble_line_with_numbers_in_it_is_no_header(tmp_path, log, preamble, blank_cell):
    table = with_blank(log) if blank_cell else log
    assert_reads_as(write(tmp_path / "logger.txt", [*preamble, *aligned(table)]), table)


def over_midnight(log: pd.DataFrame) -> tuple[list[str], list[str]]:
    """Dates and times of day of the log's rows, one a minute from 23:45 on 02.03.2026."""
    stamps = pd.Timestamp("2026-03-02 23:45:00") + pd.to_timedelta(np.arange(len(log)) * 60, unit="s")
    return list(stamps.strftime("%d.%m.%Y")), list(stamps.strftime("%H:%M:%S"))


@pytest.mark.parametrize("flush", ["left", "right"])
def test_a_german_date_and_time_in_two_columns_read_as_the_semicolon_csv_reads_them(tmp_path, log, flush):
    dates, times = over_midnight(log)
    german = with_blank(log).drop(columns="time_s").rename(columns={"error_um": "Fehler_um"})
    german.insert(0, "Zeit", times)
    german.insert(0, "Datum", dates)
    path = write(tmp_path / "messung.txt", aligned(german, flush=flush, gap=1))
    assert path.read_text().splitlines()[0].split() == ["Datum", "Zeit", "T1", "T2", "T3", "Fehler_um"]
    assert_reads_as(path, german)
    german.to_csv(tmp_path / "messung.csv", sep=";", index=False)
    run, csv = (load_run(tmp_path / name, temps=TEMPS, resample=60.0) for name in ("messung.txt", "messung.csv"))
    assert run.time_name == csv.time_name == "Datum Zeit"  # the date and the time of day read as one stamp
    assert run.clock_origin_s == csv.clock_origin_s == pd.Timestamp("2026-03-02 23:45:00").timestamp()
    np.testing.assert_array_equal(run.time, np.arange(len(log)) * 60.0)  # on past midnight
    np.testing.assert_array_equal(run.temps, csv.temps)
    np.testing.assert_array_equal(run.error, log["error_um"].to_numpy())


def test_datum_zeit_as_one_name_over_a_date_and_a_time_is_one_time_stamp(tmp_path, log):
    dates, times = over_midnight(log)
    stamps = [f"{date} {time}" for date, time in zip(dates, times)]
    stamped = with_blank(log).drop(columns="time_s")
    stamped.insert(0, "Datum Zeit", stamps)
    path = write(tmp_path / "messung.txt", aligned(stamped, flush="left", gap=1))
    assert path.read_text().splitlines()[0].startswith("Datum Zeit          T1")
    assert_reads_as(path, stamped)
    run = load_run(path, temps=TEMPS, resample=60.0)
    assert run.time_name == "Datum Zeit"
    np.testing.assert_array_equal(run.time, np.arange(len(log)) * 60.0)
    np.testing.assert_array_equal(run.error, log["error_um"].to_numpy())


@pytest.mark.parametrize("flush", ["left", "right"])
def test_names_one_space_apart_over_wider_aligned_columns_name_them_in_order(tmp_path, log, flush):
    blank = with_blank(log)
    lines = aligned(blank, flush=flush, gap=4)
    lines[0] = " ".join(COLUMNS)
    path = write(tmp_path / "report.txt", lines)
    assert len(lines[BLANK_ROW + 1].split()) == len(COLUMNS) - 1
    read = assert_reads_as(path, blank)
    assert np.isnan(read.loc[BLANK_ROW, BLANK_COLUMN])


def test_names_with_spaces_one_space_apart_over_flush_left_columns(tmp_path, log):
    named = with_blank(log).rename(columns={"T1": "Temp Spindel", "T2": "Temp Bett"})
    assert "Temp Spindel Temp Bett T3" in aligned(named, flush="left", gap=1)[0]
    assert_reads_as(write(tmp_path / "report.txt", aligned(named, flush="left", gap=1)), named)


UNITS = {
    "plain": ["s", "°C", "°C", "°C", "µm"],
    "bracketed": ["[s]", "[°C]", "[°C]", "[°C]", "[um]"],
    "deg C": ["s", "deg C", "deg C", "deg C", "um"],
    "[deg C]": ["[s]", "[deg C]", "[deg C]", "[deg C]", "[um]"],
}


@pytest.mark.parametrize("units", UNITS.values(), ids=UNITS.keys())
@pytest.mark.parametrize("flush, gap", [("right", 2), ("left", 2), ("left", 1), ("right", 1)])
@pytest.mark.parametrize("names", [{}, {"T1": "Temp T1", "T2": "Temp T2"}], ids=["names", "spaced names"])
def test_a_units_row_under_the_header_is_read_as_the_columns_units(tmp_path, log, units, flush, gap, names):
    table = log.rename(columns=names)
    path = write(tmp_path / "units.txt", aligned(table, [units], flush=flush, gap=gap))
    read = assert_reads_as(path, table)
    assert read.attrs["text_rows"] == [dict(zip(table.columns, units))]


@pytest.mark.parametrize("flush", ["left", "right"])
def test_fahrenheit_and_millimetres_of_a_units_row_with_spaces_are_converted(tmp_path, log, flush):
    logged = log.copy()
    logged[TEMPS] = (log[TEMPS] * 9.0 / 5.0 + 32.0).round(2)
    logged["error_um"] = log["error_um"] / 1000.0
    logged = logged.rename(columns={"error_um": "Z drift"})
    units = ["[s]", "[deg F]", "[deg F]", "[deg F]", "[mm]"]
    path = write(tmp_path / "imperial.txt", aligned(logged, [units], flush=flush, gap=1, decimals=5))
    run = load_run(path, temps=TEMPS, error="Z drift")
    np.testing.assert_allclose(run.temps, (logged[TEMPS].to_numpy() - 32.0) * 5.0 / 9.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.error, log["error_um"].to_numpy(), rtol=0, atol=1e-9)
    assert any("'T1' from °F" in note and "'Z drift' from mm" in note for note in run.notes)


@pytest.mark.parametrize(
    "empty, at",
    [(["spare"], [2]), (["T4"], [5]), (["T4 spare"], [3]), (["s1", "s2"], [1, 4]), (["Kanal 5"], [0])],
)
def test_a_named_column_empty_in_every_row_is_read_as_missing_values(tmp_path, log, empty, at):
    table = log.copy()
    for name, position in zip(empty, at):
        table.insert(position, name, np.nan)
    path = write(tmp_path / "report.txt", aligned(table))
    assert len(path.read_text().splitlines()[1].split()) == len(COLUMNS)
    read = assert_reads_as(path, table)
    assert read[empty].isna().all().all() and read[COLUMNS].notna().all().all()


def test_an_empty_sensor_column_is_left_out_of_the_inputs_as_in_a_csv(tmp_path, log):
    table = log.assign(T4=np.nan)[["time_s", "T1", "T4", "T2", "T3", "error_um"]]
    path = write(tmp_path / "report.txt", aligned(table))
    table.to_csv(tmp_path / "report.csv", index=False)
    run, csv = load_run(path), load_run(tmp_path / "report.csv")
    assert run.temp_names == csv.temp_names == ("T1", "T2", "T3")
    np.testing.assert_array_equal(run.temps, log[TEMPS].to_numpy())
    assert any("'T4' (a channel not connected)" in note for note in run.notes)


def test_more_names_one_space_apart_than_aligned_columns_is_refused_naming_the_misplaced_one(tmp_path, log, capsys):
    table = with_blank(log).assign(spare=np.nan)[["time_s", "T1", "spare", "T2", "T3", "error_um"]]
    lines = aligned(table.drop(columns="spare"), gap=4)
    lines[0] = " ".join(table.columns)
    message = refusal(write(tmp_path / "report.txt", lines), capsys)
    assert "does not name the 5 columns the values below it stand in" in message
    assert "('error_um' stands over columns 3 and 4)" in message
    assert message.endswith(
        "write each name over its column's values, two spaces or more from the next, or save the table as CSV)"
    )


def test_a_word_one_space_from_two_names_over_centred_columns_is_refused_naming_it(tmp_path, log, capsys):
    table = with_blank(log).rename(columns={"T1": "Temp A", "T2": "Temp B"})
    widths = [9, 8, 8, 8, 10]
    lines = ["  time_s  Temp A Temp B   T3    error_um"]
    lines += [
        "".join(cell(value).center(width) for value, width in zip(row, widths)).rstrip()
        for row in table.itertuples(index=False)
    ]
    message = refusal(write(tmp_path / "centred.txt", lines), capsys)
    assert "('A' stands over no column, one space from the names on both sides)" in message


def test_fit_reads_a_log_with_every_layout_at_once_as_the_plain_csv(tmp_path, log):
    table = log.assign(spare=np.nan)[["time_s", "T1", "spare", "T2", "T3", "error_um"]]
    units = ["[s]", "[deg C]", "[-]", "[deg C]", "[deg C]", "[um]"]
    lines = ["Thermal drift DMU 50", "", "", "", "Logger S/N 12345  started 2026-03-02 08:00"]
    path = write(tmp_path / "report.txt", lines + aligned(table, [units], flush="left", gap=1))
    log.to_csv(tmp_path / "plain.csv", index=False)
    models = {}
    for name, data in (("aligned", path), ("plain", tmp_path / "plain.csv")):
        args = ["fit", "--data", str(data), "--temps", ",".join(TEMPS), "--p", "0", "--quiet"]
        assert main([*args, "--recalibrate", "none", "--out", str(tmp_path / name)]) == 0
        models[name] = json.loads((tmp_path / name / "model.json").read_text())
    assert models["aligned"]["coefficients"] == models["plain"]["coefficients"]
    assert models["aligned"]["temps"] == TEMPS
