"""More logger layouts: a time column named with more words and a unit, a row of channel numbers under the
header, a title a spreadsheet padded with separators, NumPy's two-line ``#`` header, a sensor that began late
in a space-aligned table, a ``deg C`` units row in a single-spaced table, a message or a description between
the header and the readings. The truth is the table the test wrote; a layout that reads no other way than with
readings missing is refused in one line naming the file, the column and the row."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.readtable import read_table

ROWS = 40
PERIOD_S = 15
NAMES = ["time_s", "T1", "T2", "T3", "error_um"]


@pytest.fixture(scope="module")
def log() -> pd.DataFrame:
    """A warm-up of three sensors and the thermal error, every reading with two decimals."""
    time = np.arange(ROWS) * PERIOD_S
    temps = [20 + (1.5 + k) * (1 - np.exp(-time / (600 + 300 * k))) for k in range(3)]
    error = 3 * (temps[0] - 20) + 5 * (temps[1] - 20) - 2 * (temps[2] - 20)
    table = np.column_stack([time, *temps, error]).round(2)
    return pd.DataFrame(table, columns=NAMES)


def cells(row, decimal: str = ".") -> list[str]:
    """A row's cells as a logger writes them: the time whole, the rest with two decimals."""
    text = [f"{row[0]:.0f}", *("" if np.isnan(value) else f"{value:.2f}" for value in row[1:])]
    return [cell.replace(".", decimal) for cell in text]


def joined(frame: pd.DataFrame, sep: str, decimal: str = ".") -> list[str]:
    return [sep.join(cells(row, decimal)) for row in frame.itertuples(index=False)]


def right_aligned(rows: list[list[str]], width: int = 10) -> list[str]:
    return ["".join(cell.rjust(width) for cell in row) for row in rows]


def write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def assert_read(path: Path, log: pd.DataFrame, temps: list[str] | None = None, error: str | None = None):
    """The run read from ``path`` with the columns found by their names, checked against ``log``."""
    run = load_run(path, **({"error": error} if error else {}), **({"temps": temps} if temps else {}))
    np.testing.assert_array_equal(run.time, log["time_s"].to_numpy())
    np.testing.assert_array_equal(run.temps, log[["T1", "T2", "T3"]].to_numpy())
    np.testing.assert_array_equal(run.error, log["error_um"].to_numpy())
    return run


def refusal(path: Path, capsys) -> str:
    """The one line ``fit`` refuses the file with (exit status 2)."""
    assert main(["fit", "--data", str(path), "--p", "0", "--recalibrate", "none", "--out", str(path.parent)]) == 2
    message = capsys.readouterr().err.strip()
    assert len(message.splitlines()) == 1 and str(path) in message
    return message


def test_a_time_column_named_with_several_words_and_a_unit_is_the_time(tmp_path, log):
    header = '"Scan Sweep Time (Sec)","101 (C)","102 (C)","103 (C)","error_um"'
    path = write(tmp_path / "agilent.csv", [header, *joined(log, ",")])
    run = assert_read(path, log)
    assert run.temp_names == ("101 (C)", "102 (C)", "103 (C)")
    assert any("time from column 'Scan Sweep Time (Sec)'" in note for note in run.notes)


def test_a_counter_named_with_several_words_and_a_unit_does_not_take_the_time_from_time(tmp_path, log):
    """``Spindle Run Time (s)`` (hours of a spindle, a counter) before the log's ``Time``: the time is ``Time``."""
    counter = 3600.0 + 0.75 * log["time_s"]
    rows = [f"{hours:.2f}," + line for hours, line in zip(counter, joined(log, ","))]
    path = write(tmp_path / "counter.csv", ["Spindle Run Time (s),Time,T1,T2,T3,error_um", *rows])
    run = load_run(path, temps=["T1", "T2", "T3"])
    assert run.time_name == "Time"
    np.testing.assert_array_equal(run.time, log["time_s"].to_numpy())


@pytest.mark.parametrize(
    "units, scale",
    [("deg F deg F deg F um", None), ("deg C deg C deg C mm", 1e-3), ("s deg F deg F deg F", None)],
)
def test_a_single_spaced_units_row_of_two_word_units_one_short_converts_the_right_columns(tmp_path, log, units, scale):
    """``deg F deg F deg F um`` under ``time_s T1 T2 T3 error_um``: a unit short, its units were dropped whole with
    the row (°F read as °C, an error in mm as µm)."""
    fahrenheit = "deg F" in units
    written = log.copy()
    if fahrenheit:
        written[["T1", "T2", "T3"]] = written[["T1", "T2", "T3"]] * 9 / 5 + 32
    if scale:
        written["error_um"] = written["error_um"] * scale
    body = [" ".join(f"{v:.10g}" for v in row) for row in written.to_numpy()]
    header = " ".join([*NAMES[:-1], "error"])  # named without its unit: the units row gives it
    run = load_run(write(tmp_path / "short.txt", [header, units, *body]), temps=["T1", "T2", "T3"], error="error")
    np.testing.assert_allclose(run.temps, log[["T1", "T2", "T3"]].to_numpy(), atol=1e-9)
    np.testing.assert_allclose(run.error, log["error_um"].to_numpy(), atol=1e-9)
    np.testing.assert_array_equal(run.time, log["time_s"].to_numpy())


def test_a_single_spaced_units_row_two_units_short_is_refused(tmp_path, log, capsys):
    body = [" ".join(f"{v:.10g}" for v in row) for row in log.to_numpy()]
    path = write(tmp_path / "two_short.txt", [" ".join(NAMES), "deg F deg F deg F", *body])
    assert "a unit of temperature, over the time column 'time_s'" in refusal(path, capsys)


def test_a_row_of_channel_numbers_under_a_csv_header_is_left_out_with_a_note(tmp_path, log):
    path = write(tmp_path / "channels.csv", ["Time,T1,T2,T3,Error", ",101,102,103,", *joined(log, ",")])
    run = assert_read(path, log)
    assert any("1 row of channel numbers left out (row 1: 101, 102, 103 under the header" in n for n in run.notes)


def test_a_row_of_channel_numbers_under_an_aligned_header_is_left_out(tmp_path, log):
    rows = [["Time", "T1", "T2", "T3", "Error"], ["", "101", "102", "103", ""]]
    rows += [cells(row) for row in log.itertuples(index=False)]
    run = assert_read(write(tmp_path / "channels.dat", right_aligned(rows)), log)
    assert any("channel numbers left out" in note for note in run.notes)


def test_a_channel_label_in_the_time_cell_leaves_the_row_out_too(tmp_path, log):
    path = write(tmp_path / "kanal.csv", ["Zeit;T1;T2;T3;Fehler", "Kanal;1;2;3;", *joined(log, ";", ",")])
    assert_read(path, log)


@pytest.mark.parametrize("first", [",20.10,20.20,20.30,0.50", ",101,102,103,4"])
def test_a_first_row_without_a_time_that_holds_readings_is_still_refused(tmp_path, log, capsys, first):
    error = log["error_um"]
    assert error.min() < 4 < error.max()  # a channel number among the error's readings is no description
    path = write(tmp_path / "untimed.csv", ["Time,T1,T2,T3,Error", first, *joined(log, ",")])
    message = refusal(path, capsys)
    assert "row 1, column 'Time' is empty" in message and "fill in the time or delete the row" in message


def test_a_hobo_export_saved_again_by_a_spreadsheet_is_read(tmp_path, log):
    stamps = pd.Timestamp("2026-03-02 08:00:00") + pd.to_timedelta(log["time_s"], unit="s")
    header = (
        '"#","Date Time, GMT+01:00","Temp Spindle, °C (LGR S/N: 2001)","Temp Bed, °C (LGR S/N: 2002)",'
        '"Temp Col, °C (LGR S/N: 2003)","error_um"'
    )
    rows = [
        f"{k + 1},{stamp:%m/%d/%y %I:%M:%S %p}," + ",".join(cells(row)[1:])
        for k, (stamp, row) in enumerate(zip(stamps, log.itertuples(index=False)))
    ]
    path = write(tmp_path / "hobo.csv", ["Plot Title: 2001,,,,,", header, *rows])
    run = assert_read(path, log)
    assert run.temp_names[0] == "Temp Spindle, °C (LGR S/N: 2001)"


def test_a_padded_title_above_a_header_of_channel_numbers_is_passed_over(tmp_path, log):
    lines = ["Warmlauf Spindel;;;;", "Zeit;101;102;103;Fehler", *joined(log, ";", ",")]
    frame = read_table(write(tmp_path / "kanaele.csv", lines))[0]
    assert list(frame.columns) == ["Zeit", "101", "102", "103", "Fehler"]
    np.testing.assert_array_equal(frame.to_numpy(float), log.to_numpy())


def test_numpy_savetxt_with_a_line_of_names_and_a_line_of_units_is_read(tmp_path, log):
    path = tmp_path / "savetxt.txt"
    np.savetxt(path, log.to_numpy(), header=" ".join(NAMES) + "\ns degC degC degC um", fmt="%.4f")
    assert path.read_text().splitlines()[1] == "# s degC degC degC um"
    assert_read(path, log)


@pytest.mark.parametrize("late_rows", [1, 3, 12])
@pytest.mark.parametrize("sensor", ["T1", "T3"])
def test_a_sensor_that_began_late_in_an_aligned_table_is_named_with_its_missed_readings(
    tmp_path, log, capsys, late_rows, sensor
):
    late = log.copy()
    late.loc[: late_rows - 1, sensor] = np.nan
    rows = [NAMES, *(cells(row) for row in late.itertuples(index=False))]
    path = write(tmp_path / "late.dat", right_aligned(rows))
    frame = read_table(path)[0]
    assert list(frame.columns) == NAMES  # the header is not lost
    np.testing.assert_array_equal(frame.to_numpy(float), late.to_numpy())
    message = refusal(path, capsys)
    assert f"row 1, column '{sensor}' is empty ({late_rows} non-finite value(s) in that column)" in message


@pytest.mark.parametrize("names", [NAMES, ["time", "T_spindle", "T_bed", "T_column", "error"]], ids=["time_s", "time"])
def test_a_units_row_with_deg_c_under_a_single_spaced_header_is_read(tmp_path, log, names):
    path = write(tmp_path / "single.txt", [" ".join(names), "s deg C deg C deg C um", *joined(log, " ")])
    frame = read_table(path)[0]
    assert list(frame.columns) == names and frame.attrs["text_rows"][0][names[1]] == "deg C"
    np.testing.assert_array_equal(frame.to_numpy(float), log.to_numpy())


MESSAGE, DESCRIPTION = "Logging started", "elapsed spindle nose bed column probe"


@pytest.mark.parametrize(
    "sep, aligned, between",
    [
        (" ", False, MESSAGE),
        ("\t", False, MESSAGE),
        (" ", True, MESSAGE),
        (" ", False, DESCRIPTION),
        (" ", True, DESCRIPTION),
    ],
    ids=["single-spaced", "tabs", "aligned", "description-single-spaced", "description-aligned"],
)
def test_a_message_or_a_description_under_the_header_is_no_header(tmp_path, log, sep, aligned, between):
    rows = [NAMES, *(cells(row) for row in log.itertuples(index=False))]
    lines = right_aligned(rows) if aligned else [sep.join(row) for row in rows]
    path = write(tmp_path / "message.txt", [lines[0], "  " + between if aligned else between, *lines[1:]])
    assert_read(path, log)
