"""Which line above a table's body is its header, where a title, a row of units or a description stands near
it: each log is read back against the numbers written into it."""

from __future__ import annotations

import numpy as np
import pytest

from groupfit.data import load_runs

ROWS = 40


def readings() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    time = 15.0 * np.arange(ROWS)
    temps = 20.0 + np.round(np.column_stack([0.01 * np.arange(ROWS), 0.02 * np.arange(ROWS)]), 2)
    error = np.round(1.5 * (temps[:, 0] - 20.0) + 0.7 * (temps[:, 1] - 20.0), 2)
    return time, temps, error


def body(sep: str) -> list[str]:
    time, temps, error = readings()
    return [sep.join(f"{v:g}" for v in (t, *row, e)) for t, row, e in zip(time, temps, error)]


def assert_read_back(path, names: tuple[str, str]) -> None:
    time, temps, error = readings()
    [run] = load_runs(path, temps=list(names))
    assert run.temp_names == names
    assert np.array_equal(run.time, time) and np.allclose(run.temps, temps) and np.allclose(run.error, error)


LOGS = {
    "a column named by a number under a title": (
        ["Spindle warm-up,,,", "time_s,4711,T_bed,error_um"],
        ("4711", "T_bed"),
    ),
    "a row of units the unit list lacks, double spaced": (["time_s,T1,T2,error_um", "", "s,C,C,um"], ("T1", "T2")),
    "a description row, double spaced": (["time_s,T1,T2,error_um", "", "elapsed,front,rear,probe Z"], ("T1", "T2")),
    "a description row under a column named by a number": (
        ["time_s,T1,4711,error_um", "elapsed,front,motor,probe"],
        ("T1", "4711"),
    ),
    "a message row under an empty line": (["time_s;T1;T2;error_um", "", "Start of measurement;;;"], ("T1", "T2")),
}
"""Lines above the body, and the inputs' names the header gives; ``double spaced``: an empty line after every
row, as Python's ``csv`` module writes on Windows without ``newline=""``."""


@pytest.mark.parametrize("case", sorted(LOGS))
def test_the_header_is_the_line_that_names_the_columns(tmp_path, case):
    head, names = LOGS[case]
    sep = ";" if ";" in head[0] else ","
    rows = [f"{row}\n" for row in body(sep)] if "double spaced" in case else body(sep)
    path = tmp_path / "log.csv"
    path.write_text("\n".join([*head, *rows]) + "\n", encoding="utf-8")
    assert_read_back(path, names)


def test_a_table_split_at_single_spaces_keeps_a_units_row_without_the_times_unit(tmp_path):
    path = tmp_path / "log.txt"
    path.write_text("\n".join(["time_s T1 T2 error_um", "°C °C µm", *body(" ")]) + "\n", encoding="utf-8")
    assert_read_back(path, ("T1", "T2"))


def test_a_title_of_as_many_words_as_columns_above_an_empty_line_is_no_header(tmp_path):
    path = tmp_path / "log.dat"
    lines = ["Spindle warm up test", "", "time_s  T1  T2  error_um", *(row.replace(" ", "  ") for row in body(" "))]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert_read_back(path, ("T1", "T2"))
