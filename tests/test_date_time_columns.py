"""A log that writes the date and the time of day in two columns reads as its twin with one joined stamp column
does, and as pandas reads the two strings with the form they were written in: the seconds, the clock fields of
the model file, the fit, and a next file's continuation across a change to or from summer time."""

from __future__ import annotations

import dataclasses
import datetime
import json
from pathlib import Path

import numpy as np
import openpyxl
import pandas as pd
import pytest
from support.clocks import cli, needs_zones

from groupfit.data import load_run, load_runs
from groupfit.errors import InputError
from groupfit.readtable import read_table

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
QUICK = ["--reference", "none", "--quiet", "--p", "0", "--ridge", "0", "--recalibrate", "none"]
ROWS, CHANGE_ROW, CUT = 240, 120, 60
JOINED = "Zeitstempel"


@dataclasses.dataclass(frozen=True)
class Layout:
    """How a logger writes its two columns: separator, decimal mark, names, the strftime forms, the change of its
    local clock the log crosses at row ``CHANGE_ROW`` (UTC, zone), and the hours the clock goes (ahead: +1)."""

    sep: str
    decimal: str
    names: tuple[str, str]
    forms: tuple[str, str]
    change: tuple[str, str]
    hours: int

    @property
    def joined_name(self) -> str:
        return " ".join(self.names)


LAYOUTS = {
    "german": Layout(";", ",", ("Datum", "Zeit"), ("%d.%m.%Y", "%H:%M:%S"), ("2026-10-25 01:00", "Europe/Berlin"), -1),
    "us": Layout(",", ".", ("Date", "Time"), ("%m/%d/%Y", "%I:%M:%S %p"), ("2026-03-08 07:00", "America/New_York"), 1),
    "iso": Layout(",", ".", ("date", "time"), ("%Y-%m-%d", "%H:%M:%S"), ("2026-11-01 06:00", "America/New_York"), -1),
}
"""A German CSV (``;``, decimal comma) over the end of summer time in Berlin, a HOBO-style export with AM/PM over
its beginning in New York (day and month of 03/07 and 03/08 told apart by the even sampling), and ISO dates over
its end in New York."""

pytestmark = needs_zones


def local_stamps(layout: Layout) -> pd.Series:
    """The paper cycle's rows stamped in the zone's local time, its clock changing at row ``CHANGE_ROW``."""
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:ROWS]
    utc_change, zone = layout.change
    utc = pd.Timestamp(utc_change, tz="UTC") + pd.to_timedelta(log["time_s"] - CHANGE_ROW * 100.0, unit="s")
    local = utc.dt.tz_convert(zone)
    offsets = local.map(lambda t: t.utcoffset().total_seconds()).to_numpy()
    assert np.flatnonzero(np.diff(offsets)).tolist() == [CHANGE_ROW - 1], "the clock changes at CHANGE_ROW"
    return local


def frame(log: pd.DataFrame, **stamps) -> pd.DataFrame:
    """The log's readings after the stamp columns ``stamps`` (name: cells)."""
    return pd.concat([pd.DataFrame(stamps, index=log.index), log], axis=1)


def twin_tables(layout: Layout) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The log with its date and time of day in two columns, and its twin with one column of both."""
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:ROWS].drop(columns="time_s")
    local = local_stamps(layout)
    date_form, time_form = layout.forms
    dates, times = local.dt.strftime(date_form), local.dt.strftime(time_form)
    return frame(log, **dict(zip(layout.names, (dates, times)))), frame(log, **{JOINED: dates + " " + times})


def write(table: pd.DataFrame, path: Path, layout: Layout) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(path, index=False, sep=layout.sep, decimal=layout.decimal)
    return path


def twin_files(folder: Path, layout: Layout, rows: slice = slice(None), stem: str = "log") -> tuple[Path, Path]:
    """The two tables written alike, under one file name in two folders (their notes name the same file)."""
    separate, joined = twin_tables(layout)
    return (
        write(separate.iloc[rows], folder / "separate" / f"{stem}.csv", layout),
        write(joined.iloc[rows], folder / "joined" / f"{stem}.csv", layout),
    )


def pandas_clock(path: Path, layout: Layout) -> tuple[np.ndarray, float, float]:
    """The truth by pandas alone: the two strings as written, joined and read in their known form, placed in the
    zone (the repeated hour told by its order): the seconds since the first row, the first row's date-time in
    the clock of the last row (seconds since 1970, read as UTC) and the hours that moved it (in seconds)."""
    cells = pd.read_csv(path, sep=layout.sep, dtype=str)
    date, time = layout.names
    wall = pd.to_datetime(cells[date] + " " + cells[time], format=" ".join(layout.forms))
    placed = wall.dt.tz_localize(layout.change[1], ambiguous="infer")
    seconds = (placed - placed.iloc[0]).dt.total_seconds().to_numpy()
    shift = (placed.iloc[-1].utcoffset() - placed.iloc[0].utcoffset()).total_seconds()
    return seconds, (wall.iloc[0] + pd.Timedelta(seconds=shift)).timestamp(), shift


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_a_date_and_a_time_of_day_read_as_the_joined_stamp_and_as_pandas_reads_them(tmp_path, name):
    layout = LAYOUTS[name]
    separate, joined = twin_files(tmp_path, layout)
    [split], [whole] = load_runs(separate), load_runs(joined)
    seconds, origin, shift = pandas_clock(separate, layout)
    np.testing.assert_array_equal(split.time, seconds)  # whole seconds, to the second and below
    np.testing.assert_array_equal(split.time, whole.time)
    assert split.clock_origin_s == whole.clock_origin_s == origin
    assert split.clock_shift_s == whole.clock_shift_s == shift == 3600.0 * layout.hours
    np.testing.assert_array_equal(split.temps, whole.temps)
    np.testing.assert_array_equal(split.error, whole.error)
    date, time = layout.names
    assert split.time_name == layout.joined_name and split.temp_names == whole.temp_names
    assert time not in split.frame.columns and date not in split.frame.columns
    assert split.notes[0] == (
        f"{separate}: time from columns '{date}' and '{time}', a date and a time of day read as one stamp, "
        f"'{layout.joined_name}' (there is no 'time_s'; --time names another)"
    )
    assert whole.notes[0] == f"{joined}: time from column '{JOINED}' (there is no 'time_s'; --time names another)"
    told = [note.replace(str(separate), str(joined)).replace(layout.joined_name, JOINED) for note in split.notes[1:]]
    assert told == list(whole.notes[1:]) and "summer time" in told[0]


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_the_fit_and_the_model_files_clock_fields_are_those_of_the_joined_twin(tmp_path, name):
    separate, joined = twin_files(tmp_path, LAYOUTS[name])
    results, models = {}, {}
    for kind, path in (("separate", separate), ("joined", joined)):
        out = tmp_path / f"{kind}_model"
        assert cli("fit", "--data", path, *QUICK, "--out", out, "--json", tmp_path / f"{kind}.json") == 0
        results[kind] = json.loads((tmp_path / f"{kind}.json").read_text())
        models[kind] = json.loads((out / "model.json").read_text())
    assert results["separate"]["coefficients"] == results["joined"]["coefficients"]
    assert models["separate"]["coefficients"] == models["joined"]["coefficients"]
    assert models["separate"]["training"]["time"] == LAYOUTS[name].joined_name
    [split], [whole] = (model["training"]["recordings"] for model in models.values())
    clock = ("first_time_s", "last_time_s", "period_s", "clock_origin_s", "clock_shift_s", "end_state")
    assert {k: split[k] for k in clock} == {k: whole[k] for k in clock}
    assert split["clock_shift_s"] == 3600.0 * LAYOUTS[name].hours


def replayed(tmp_path: Path, model: Path, data: Path, *more) -> dict:
    report = tmp_path / f"{data.parent.name}_{data.stem}.replay.json"
    assert cli("replay", model, "--data", data, "--json", report, *more) == 0
    return json.loads(report.read_text())


@pytest.mark.parametrize("name", ["german", "us"])
def test_a_next_file_continues_the_modelling_file_across_the_change_as_the_joined_twin_does(tmp_path, capsys, name):
    layout = LAYOUTS[name]
    first = twin_files(tmp_path, layout, slice(None, CUT), "first")
    rest = twin_files(tmp_path, layout, slice(CUT, None), "rest")
    results = {}
    for kind, modelling, following in zip(("separate", "joined"), first, rest):
        out = tmp_path / f"{kind}_model"
        assert cli("fit", "--data", modelling, *QUICK, "--out", out) == 0
        capsys.readouterr()
        results[kind] = replayed(tmp_path, out / "model.json", following)
        assert "rest's clock continues the modelling recording" in capsys.readouterr().out
    assert results["separate"]["history_samples"] == results["joined"]["history_samples"] == CUT
    residuals = {kind: [s["residual_um"] for s in result["samples"]] for kind, result in results.items()}
    assert residuals["separate"] == residuals["joined"]


def test_compare_validates_a_next_file_in_two_columns_as_the_continuation_of_the_modelling_file(tmp_path, capsys):
    layout = LAYOUTS["german"]
    first = twin_files(tmp_path, layout, slice(None, CUT), "first")
    rest = twin_files(tmp_path, layout, slice(CUT, None), "rest")
    scores = {}
    for kind, modelling, following in zip(("separate", "joined"), first, rest):
        report = tmp_path / f"{kind}_compare.json"
        args = ["--data", modelling, "--validate", following, "--pmax", "1", "--quiet", "--json", report]
        assert cli("compare", *args, "--out", tmp_path / f"{kind}_compare") == 0
        assert "rest continues first" in capsys.readouterr().out
        rows = json.loads(report.read_text())["rows"]
        scores[kind] = {row["model"]: row["rms_um"] for row in rows if row["run"] == "rest"}
    assert scores["separate"] == scores["joined"] and len(scores["joined"]) >= 2


def test_time_may_name_the_time_of_day_the_date_or_both(tmp_path, capsys):
    layout = LAYOUTS["german"]
    separate, _ = twin_files(tmp_path, layout)
    [found] = load_runs(separate)
    for asked in ("Zeit", "Datum", "Datum Zeit"):
        [run] = load_runs(separate, time=asked)
        np.testing.assert_array_equal(run.time, found.time)
        assert run.time_name == "Datum Zeit" and run.clock_origin_s == found.clock_origin_s
        told = [note for note in run.notes if "time from" in note]
        assert told == ([] if asked == "Datum Zeit" else [found.notes[0].split(" (there is no")[0]])
    first, rest = (
        twin_files(tmp_path / part, layout, rows, part)[0]
        for part, rows in (("first", slice(None, CUT)), ("rest", slice(CUT, None)))
    )
    out = tmp_path / "model"
    assert cli("fit", "--data", first, "--time", "Zeit", *QUICK, "--out", out) == 0
    assert json.loads((out / "model.json").read_text())["training"]["time"] == "Datum Zeit"
    capsys.readouterr()
    for more in ((), ("--time", "Zeit")):
        result = replayed(tmp_path, out / "model.json", rest, *more)
        assert result["history_samples"] == CUT
        assert "rest's clock continues the modelling recording" in capsys.readouterr().out


def workbook(path: Path, table: pd.DataFrame, formats: dict[str, str]) -> Path:
    """The table as a workbook written cell by cell (``formats``: a column's number format), as a spreadsheet
    saves date cells and time cells (pandas writes a ``datetime.time`` as text)."""
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(list(table.columns))
    for row in table.itertuples(index=False):
        sheet.append([value.item() if isinstance(value, np.generic) else value for value in row])
    for k, column in enumerate(table.columns, start=1):
        for (cell,) in sheet.iter_rows(min_row=2, min_col=k, max_col=k):
            cell.number_format = formats.get(column, cell.number_format)
    book.save(path)
    return path


def other_twins(folder: Path) -> dict[str, Path]:
    """The German log as a workbook of date cells and time cells, one of date cells and fractions of a day
    formatted as times, one of fractions saved as plain numbers, a CSV of ISO dates and fractions, and a table
    aligned by spaces."""
    local = local_stamps(LAYOUTS["german"]).dt.tz_localize(None)
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:ROWS].drop(columns="time_s")
    midnight = local.dt.normalize()
    fractions = (local - midnight).dt.total_seconds() / 86400.0
    dates = [t.date() for t in local]
    cells = {"Datum": "DD.MM.YYYY", "Zeit": "hh:mm:ss"}
    paths = {
        "cells.xlsx": workbook(folder / "cells.xlsx", frame(log, Datum=dates, Zeit=[t.time() for t in local]), cells),
        "formatted.xlsx": workbook(folder / "formatted.xlsx", frame(log, Datum=dates, Zeit=fractions), cells),
        "numbers.xlsx": workbook(
            folder / "numbers.xlsx", frame(log, Datum=dates, Zeit=fractions), cells | {"Zeit": "General"}
        ),
    }
    frame(log, Datum=midnight.dt.strftime("%Y-%m-%d"), Zeit=fractions).to_csv(folder / "fractions.csv", index=False)
    aligned = frame(log, Datum=local.dt.strftime("%d.%m.%Y"), Zeit=local.dt.strftime("%H:%M:%S"))
    (folder / "aligned.txt").write_text(aligned.to_string(index=False) + "\n")
    return {**paths, "fractions.csv": folder / "fractions.csv", "aligned.txt": folder / "aligned.txt"}


def test_a_workbooks_date_cells_and_time_cells_read_as_the_joined_stamp(tmp_path):
    paths = other_twins(tmp_path)
    for name in ("cells.xlsx", "formatted.xlsx", "numbers.xlsx"):  # what the reader gives
        cells, _, _ = read_table(paths[name])
        assert pd.api.types.is_datetime64_any_dtype(cells["Datum"]), name
        assert (cells["Datum"] == cells["Datum"].dt.normalize()).all(), name
        times = cells["Zeit"]
        is_time = [isinstance(cell, datetime.time) for cell in times]
        assert all(is_time) if name != "numbers.xlsx" else pd.api.types.is_float_dtype(times), name
    _, joined = twin_files(tmp_path, LAYOUTS["german"])
    [whole] = load_runs(joined)
    for name, path in paths.items():
        [run] = load_runs(path)
        assert run.time_name == "Datum Zeit", name
        np.testing.assert_array_equal(run.time, whole.time)
        assert (run.clock_origin_s, run.clock_shift_s) == (whole.clock_origin_s, whole.clock_shift_s), name
        np.testing.assert_array_equal(run.temps, whole.temps)


def german_log(tmp_path: Path, **columns) -> Path:
    """The German log with its time columns replaced by ``columns`` (name: cells, as many rows as the first
    has), written as a CSV."""
    separate, _ = twin_tables(LAYOUTS["german"])
    rows = len(next(iter(columns.values())))
    table = separate.drop(columns=["Datum", "Zeit"]).iloc[:rows]
    for position, (name, cells) in enumerate(columns.items()):
        table.insert(position, name, np.asarray(cells))
    return write(table, tmp_path / "log.csv", LAYOUTS["german"])


def refusal(tmp_path: Path, data: Path) -> int:
    """The exit status of a fit of ``data``."""
    return cli("fit", "--data", data, *QUICK, "--out", tmp_path / "unused")


def test_a_date_beside_no_time_of_day_is_not_joined_and_read_as_before(tmp_path, capsys):
    separate, _ = twin_tables(LAYOUTS["german"])
    dates = separate["Datum"]
    for neighbour in (None, ("Schicht", ["Früh"] * ROWS), ("Zeit", ["n. a."] * ROWS)):
        path = german_log(tmp_path, Datum=dates, **dict([neighbour] if neighbour else []))
        assert refusal(tmp_path, path) == 2
        assert f"row 1, column 'Datum': '{dates[0]}' is neither a number of seconds nor a date-time" in (
            capsys.readouterr().err
        )
    counted = german_log(tmp_path, Datum=dates, Zeit=100.0 * np.arange(ROWS))  # seconds, not times of day
    [run] = load_runs(counted)
    assert run.time_name == "Zeit" and "Datum" in run.frame.columns and run.clock_origin_s is None
    np.testing.assert_array_equal(run.time, 100.0 * np.arange(ROWS))


def test_a_time_of_day_alone_and_a_date_alone_keep_their_reading(tmp_path):
    separate, _ = twin_tables(LAYOUTS["german"])
    [alone] = load_runs(german_log(tmp_path, Zeit=separate["Zeit"].iloc[:CHANGE_ROW]))
    assert alone.time_name == "Zeit" and alone.clock_origin_s is None  # a time of day names no date
    np.testing.assert_array_equal(alone.time, 100.0 * np.arange(CHANGE_ROW))
    with pytest.raises(InputError, match="column 'Zeit' goes back one hour at row 121"):  # no date, no zone
        load_runs(german_log(tmp_path, Zeit=separate["Zeit"]))
    days = pd.date_range("2026-10-01", periods=ROWS, freq="D").strftime("%Y-%m-%d")
    [daily] = load_runs(german_log(tmp_path, Datum=days))
    assert daily.time_name == "Datum" and daily.period == 86400.0
    assert daily.clock_origin_s == pd.Timestamp("2026-10-01").timestamp()


def test_an_empty_time_of_day_is_refused_as_an_empty_stamp(tmp_path, capsys):
    layout = LAYOUTS["german"]
    separate, joined = twin_tables(layout)
    for column, table in (("Zeit", separate), (JOINED, joined)):
        broken = table.copy()
        broken.loc[6, column] = None
        path = write(broken, tmp_path / column / "log.csv", layout)
        assert refusal(tmp_path, path) == 2
        assert f"{path}: row 7, column '{column}' is empty; fix or remove that row" in capsys.readouterr().err
        with pytest.raises(InputError, match=f"row 7, column '{column}' is empty"):
            load_run(path)


@pytest.mark.parametrize("missing", ["one row", "the last row", "all but the first row"])
def test_a_date_missing_where_the_time_of_day_is_written_leaves_the_time_of_day_read_alone(tmp_path, missing):
    """A date column not written on every row (left empty on the last row, written on the first alone) is no
    date of every row: the time of day is read alone, as before the two were joined."""
    separate, _ = twin_tables(LAYOUTS["german"])
    dates = separate["Datum"].iloc[:CHANGE_ROW].astype(object).copy()
    where = {"one row": [6], "the last row": [CHANGE_ROW - 1], "all but the first row": list(range(1, CHANGE_ROW))}
    dates.iloc[where[missing]] = None
    [run] = load_runs(german_log(tmp_path, Datum=dates, Zeit=separate["Zeit"].iloc[:CHANGE_ROW]))
    assert run.time_name == "Zeit" and run.clock_origin_s is None
    np.testing.assert_array_equal(run.time, 100.0 * np.arange(CHANGE_ROW))


def test_a_start_date_over_a_clock_that_passes_midnight_is_not_joined(tmp_path):
    """The date the run started on, on every row, while the time of day rolls past midnight: joined, the clock
    went back a day; the time of day is read alone, through midnight, as before."""
    stamps = pd.date_range("2026-03-02 23:00", periods=30, freq="5min")
    [run] = load_runs(german_log(tmp_path, Datum=["02.03.2026"] * 30, Zeit=stamps.strftime("%H:%M:%S")))
    assert run.time_name == "Zeit"
    np.testing.assert_array_equal(run.time, 300.0 * np.arange(30))


def test_numbers_below_one_under_time_beside_one_date_are_not_taken_for_fractions_of_a_day(tmp_path):
    """``Time`` 0.0, 0.0167 … (hours) beside one date: fractions of a day only where the date changes."""
    hours = np.round(np.arange(30) / 60.0, 6)
    [run] = load_runs(german_log(tmp_path, Datum=["02.03.2026"] * 30, Zeit=hours))
    assert run.time_name == "Zeit" and run.clock_origin_s is None
    np.testing.assert_allclose(run.time, hours)


def test_a_time_of_day_that_is_none_is_named_with_its_row(tmp_path):
    layout = LAYOUTS["german"]
    separate, _ = twin_tables(layout)
    separate.loc[9, "Zeit"] = "25:70:00"
    path = write(separate, tmp_path / "log.csv", layout)
    with pytest.raises(InputError, match=r"row 10, column 'Datum Zeit': '\d\d\.10\.2026 25:70:00' is not a date-time"):
        load_run(path)


def under_the_header(path: Path, line: str, folder: str = "with_row") -> Path:
    """The file with ``line`` written between its header and its first row, under the same name in ``folder``
    beside it (its notes name the same file)."""
    header, rest = path.read_text(encoding="utf-8").split("\n", 1)
    written = path.parent / folder / path.name
    written.parent.mkdir()
    written.write_text(f"{header}\n{line}\n{rest}", encoding="utf-8")
    return written


@pytest.mark.parametrize(
    "row", [";;101;102;103;104;105;106;107;;;", "Ch;Ch;1;2;3;4;5;6;7;;;", "Kanal;;1;2;3;4;5;6;7;;;"]
)
def test_a_row_of_channel_numbers_over_a_date_and_a_time_of_day_is_left_out_as_over_one_stamp(tmp_path, row):
    layout = LAYOUTS["german"]
    separate, _ = twin_files(tmp_path, layout)
    channels = under_the_header(separate, row)
    [plain], [run] = load_runs(separate), load_runs(channels)
    seconds, origin, shift = pandas_clock(separate, layout)
    np.testing.assert_array_equal(run.time, seconds)
    np.testing.assert_array_equal(run.time, plain.time)
    assert (run.clock_origin_s, run.clock_shift_s) == (plain.clock_origin_s, plain.clock_shift_s) == (origin, shift)
    assert run.time_name == plain.time_name == "Datum Zeit" and run.temp_names == plain.temp_names
    assert list(run.frame.columns) == list(plain.frame.columns)
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.error, plain.error)
    shown = ", ".join(cell for cell in row.split(";")[2:] if cell)
    told = f"{channels}: 1 row of channel numbers left out (row 1: {shown} under the header, without a time"
    assert [note.replace(str(channels), str(separate)) for note in run.notes if not note.startswith(told)] == list(
        plain.notes
    )
    assert run.notes[1].startswith(told)


def test_a_first_row_with_its_date_and_time_or_with_a_reading_among_the_others_is_no_channel_row(tmp_path):
    layout = LAYOUTS["german"]
    separate, _ = twin_files(tmp_path, layout)
    first = separate.read_text(encoding="utf-8").splitlines()[1].split(";")
    before = pd.to_datetime(" ".join(first[:2]), format=" ".join(layout.forms)) - pd.Timedelta(seconds=100)
    stamp = [f"{before:%d.%m.%Y}", f"{before:%H:%M:%S}"]
    rising = [str(k) for k in range(1, 8)]
    [plain], [run] = load_runs(separate), load_runs(under_the_header(separate, ";".join([*stamp, *rising, *first[9:]])))
    np.testing.assert_array_equal(run.time, np.concatenate([[0.0], plain.time + 100.0]))
    readings = ["T1", "T2", "T3", "T4", "T5", "T6", "T_amb"]
    np.testing.assert_array_equal(run.frame[readings].iloc[0].to_numpy(dtype=float), np.arange(1.0, 8.0))
    np.testing.assert_array_equal(run.temps[1:], plain.temps)
    assert not any("channel numbers" in note for note in run.notes)
    unread = {
        ";;101;102;103;104;105;106;107;4;;": "row 1, column 'Datum' is empty",  # 4 µm: among the error's readings
        ";".join([*stamp, *rising, "", "", ""]): "row 1, column 'error_um' is empty",
    }
    for k, (row, refused) in enumerate(unread.items()):
        with pytest.raises(InputError, match=refused):
            load_runs(under_the_header(separate, row, f"unread_{k}"))
