"""Tables aligned in columns by spaces (pandas' ``to_string``, a logger's fixed-width report) whose rows do not all
split at their spaces into the header's names: an empty cell, names with a space in them, an index column. They
are read by the position of their cells; the truth is the same table written as a plain CSV. A table whose
columns do not line up is refused in one line naming the file and the row."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.readtable import read_table

PAPER = Path(__file__).resolve().parents[1] / "datasets" / "paper_cycle.csv"
COLUMNS = ["time_s", "T1", "T2", "T3", "T_amb", "speed_rpm", "error_um"]
TEMPS = ["T1", "T2", "T3"]
SPACED = {"time_s": "Time s", "T1": "Temp Spindel", "T2": "Temp Lager", "T3": "Temp Bett", "error_um": "Z drift um"}


@pytest.fixture(scope="module")
def log() -> pd.DataFrame:
    """The first 40 rows of the shipped run, floats written with two decimals as a report does."""
    return pd.read_csv(PAPER)[COLUMNS].head(40).astype(float)


def same_values(path: Path, truth: Path) -> pd.DataFrame:
    """The table read from ``path``, checked to hold the names and values of the one read from ``truth``."""
    read, expected = read_table(path)[0], read_table(truth)[0]
    assert list(read.columns) == list(expected.columns)
    np.testing.assert_array_equal(read.to_numpy(float), expected.to_numpy(float))
    return read


def with_blank(log: pd.DataFrame, row: int, column: str) -> pd.DataFrame:
    blank = log.copy()
    blank.loc[row, column] = np.nan
    return blank


@pytest.mark.parametrize("column", ["T2", "time_s", "error_um", "speed_rpm"])
def test_an_empty_cell_of_a_fixed_width_export_is_missing_in_its_own_column(tmp_path, log, column):
    blank = with_blank(log, 12, column)
    path, truth = tmp_path / "report.txt", tmp_path / "plain.csv"
    path.write_text(blank.to_string(index=False, na_rep="", float_format="%.2f") + "\n")
    blank.to_csv(truth, index=False)
    assert len(path.read_text().splitlines()[13].split()) == len(COLUMNS) - 1  # split at spaces: a value fewer
    read = same_values(path, truth)
    assert np.isnan(read.loc[12, column]) and read.drop(columns=column).notna().all().all()


def test_the_empty_cell_is_refused_by_fit_naming_its_row_and_column_and_resample_fills_it(tmp_path, log, capsys):
    blank = with_blank(log, 20, "T2")
    path, truth = tmp_path / "report.txt", tmp_path / "plain.csv"
    path.write_text(blank.to_string(index=False, na_rep="", float_format="%.2f") + "\n")
    blank.to_csv(truth, index=False)
    assert main(["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--out", str(tmp_path / "o")]) == 2
    assert "row 21, column 'T2' is empty" in capsys.readouterr().err
    filled = load_run(path, temps=TEMPS, resample=100.0)
    np.testing.assert_array_equal(filled.temps, load_run(truth, temps=TEMPS, resample=100.0).temps)
    assert filled.temps[20, 1] == pytest.approx(log.loc[19:21:2, "T2"].mean())


def test_names_with_spaces_over_right_aligned_numbers_are_kept_whole(tmp_path, log):
    spaced = log.rename(columns=SPACED)
    path, truth = tmp_path / "to_string.txt", tmp_path / "plain.csv"
    path.write_text(spaced.to_string(index=False) + "\n")
    spaced.to_csv(truth, index=False)
    assert "Temp Spindel" in same_values(path, truth).columns


def test_names_with_spaces_and_an_empty_cell_together(tmp_path, log):
    spaced = with_blank(log, 7, "T3").rename(columns=SPACED)
    path, truth = tmp_path / "to_string.txt", tmp_path / "plain.csv"
    path.write_text(spaced.to_string(index=False, na_rep="") + "\n")
    spaced.to_csv(truth, index=False)
    assert np.isnan(same_values(path, truth).loc[7, "Temp Bett"])


@pytest.mark.parametrize("names", [{}, SPACED, {"T2": "T2 spindle"}, {"T1": "T1 spindle", "T3": "T3 bed"}])
def test_the_index_of_a_to_string_export_is_kept_as_a_csvs_index_column_is(tmp_path, log, names):
    indexed = log.rename(columns=names)
    path, truth = tmp_path / "to_string.txt", tmp_path / "indexed.csv"
    path.write_text(indexed.to_string() + "\n")
    indexed.to_csv(truth)  # the index written as a column without a name
    assert same_values(path, truth).columns[0] == "Unnamed: 0"
    if not names:
        run = load_run(path)
        assert "Unnamed: 0" not in run.temp_names and run.temp_names == load_run(truth).temp_names


def test_a_table_of_spaces_whose_columns_do_not_line_up_is_refused_naming_its_row(tmp_path, log):
    lines = [" ".join(COLUMNS)] + [" ".join(f"{value:g}" for value in row) for row in log.to_numpy()]
    fields = lines[15].split(" ")
    lines[15] = " ".join(fields[:2] + fields[3:])  # T2 left out, its neighbours one space apart
    path = tmp_path / "ragged.dat"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as refused:
        read_table(path)
    message = str(refused.value)
    assert len(message.splitlines()) == 1
    assert str(path) in message and "row 15 (" in message and ") has 6 value(s)" in message
    assert "fill the empty cell" in message
    assert "fill the empty cell, or save the table as CSV" in message
