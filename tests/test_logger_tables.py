"""Logs as loggers and controllers write them, read without rewriting: decimal commas, a Windows encoding,
a preamble, a units row, trailing separators and text time stamps. The truth is the same run written as a
plain comma-separated table in seconds."""

from __future__ import annotations

import bz2
import codecs
import gzip
import json
import lzma
import re
import zipfile

import numpy as np
import pandas as pd
import pytest
from support import same_run
from test_switching_models import SYNTHETIC

from groupfit.cli import main
from groupfit.columns import is_ambient_name
from groupfit.data import load_run
from groupfit.default_columns import default_temperature_columns, error_like_columns
from groupfit.errors import InputError
from groupfit.readtable import read_table
from groupfit.sweep.datasets import read_datasets
from groupfit.textlayout import layout_of, read_text_table
from groupfit.timestamps import text_seconds, time_like_columns

TEMPS = ["T1", "T2", "T3", "T4"]


@pytest.fixture(scope="module")
def plain():
    return load_run(SYNTHETIC, temps=TEMPS)


@pytest.fixture(scope="module")
def frame():
    return pd.read_csv(SYNTHETIC)


@pytest.mark.parametrize("sep", [";", "\t"])
def test_decimal_commas_read_as_the_plain_table(tmp_path, frame, plain, sep):
    path = tmp_path / "eu.csv"
    frame.to_csv(path, sep=sep, decimal=",", index=False)
    assert "," in path.read_text().splitlines()[1]  # the numbers carry decimal commas
    assert layout_of(path.read_text()).decimal == ","
    same_run(load_run(path, temps=TEMPS), plain)


def test_a_comma_separated_table_never_takes_commas_as_decimal_marks(frame):
    assert layout_of(frame.to_csv(index=False)).decimal == "."


def test_a_windows_encoded_header_with_units_in_the_names(tmp_path, frame, plain):
    named = frame.rename(columns={"T1": "T1 [°C]", "error_um": "error [µm]"})
    path = tmp_path / "windows.csv"
    path.write_bytes(named.to_csv(index=False, sep=";", decimal=",").encode("cp1252"))
    with pytest.raises(UnicodeDecodeError):
        path.read_bytes().decode("utf-8")
    run = load_run(path, temps=["T1 [°C]", "T2", "T3", "T4"], error="error [µm]")
    assert run.temp_names[0] == "T1 [°C]"
    same_run(run, plain)


def test_a_byte_order_mark_is_not_part_of_the_first_name(tmp_path, frame, plain):
    path = tmp_path / "bom.csv"
    path.write_bytes(frame.to_csv(index=False).encode("utf-8-sig"))
    same_run(load_run(path, temps=TEMPS), plain)


def test_a_preamble_and_a_units_row_are_passed_over(tmp_path, frame, plain):
    body = frame.to_csv(index=False, sep=";", decimal=",", lineterminator="\r\n").split("\r\n", 1)
    units = ";".join(
        "s" if c == "time_s" else "µm" if c == "error_um" else "" if c == "spindle_on" else "°C" for c in frame
    )
    preamble = "Data logger DL-7, firmware 2.1\r\nStart;02.03.2026 08:00\r\n\r\n"
    path = tmp_path / "logger.csv"
    path.write_bytes((preamble + body[0] + "\r\n" + units + "\r\n" + body[1]).encode("cp1252"))
    layout = layout_of(path.read_bytes().decode("cp1252"))
    assert (layout.header_line, layout.sep, layout.decimal) == (3, ";", ",")
    same_run(load_run(path, temps=TEMPS), plain)


def test_a_first_row_with_a_number_in_it_is_data_not_units(tmp_path, frame):
    path = tmp_path / "bad_first_row.csv"
    text = frame.to_csv(index=False).splitlines()
    cells = text[1].split(",")
    text[1] = ",".join(["n/a"] * (len(cells) - 1) + [cells[-1]])
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match="row 1, column 'time_s'"):
        load_run(path, temps=TEMPS)


def test_a_separator_closing_every_data_row_does_not_shift_the_columns(tmp_path, frame, plain):
    lines = frame.to_csv(index=False).strip().splitlines()
    path = tmp_path / "trailing.csv"
    path.write_text(lines[0] + "\n" + "\n".join(line + "," for line in lines[1:]) + "\n")
    same_run(load_run(path, temps=TEMPS), plain)


def test_a_row_with_more_values_than_names_is_refused(tmp_path):
    path = tmp_path / "extra.csv"
    path.write_text("time_s,T1,error_um\n0,20,1,9\n1,20,1\n")
    with pytest.raises(InputError, match=r"extra.csv: not a readable CSV table \(row 1 has 4 values but the header"):
        read_table(path)


@pytest.mark.parametrize("row", [1, 2, 52, 199])
@pytest.mark.parametrize("extra", [",door opened", ",1,2"])
def test_a_note_typed_into_one_row_is_refused_naming_that_row_not_read_as_the_header(tmp_path, row, extra):
    lines = ["time_s,T1,T2,error_um"] + [
        f"{60 * k},{20 + 0.01 * k:.2f},{21 + 0.02 * k:.2f},{0.1 * k:.1f}" for k in range(200)
    ]
    lines[row] += extra
    path = tmp_path / "note.csv"
    path.write_text("\n".join(lines) + "\n")
    width = 4 + extra.count(",")
    with pytest.raises(
        InputError, match=rf"note.csv: not a readable CSV table \(row {row} has {width} values but the header names 4"
    ):
        read_table(path)


def test_the_sweep_reads_file_contents_as_the_verbs_read_the_file(tmp_path, frame):
    path = tmp_path / "eu.csv"
    frame.to_csv(path, sep=";", decimal=",", index=False)
    from_bytes, header = read_text_table(path.read_bytes())
    from_file, _, _ = read_table(path)
    pd.testing.assert_frame_equal(from_bytes, from_file)
    assert header == list(frame.columns)


START = pd.Timestamp("2026-03-28 22:00:00")


def stamped(frame, form, start=START):
    """The run with its seconds written as wall-clock text in ``form``."""
    out = frame.copy()
    stamps = start + pd.to_timedelta(frame["time_s"] - frame["time_s"].iloc[0], unit="s")
    out["time_s"] = [t.strftime(form) for t in stamps]
    return out


@pytest.mark.parametrize(
    "form",
    [
        "%Y-%m-%d %H:%M:%S",
        "%Y-%m-%dT%H:%M:%S",
        "%d.%m.%Y %H:%M:%S",
        "%d.%m.%y %H:%M:%S",
        "%Y/%m/%d %H:%M:%S",
        "%m/%d/%Y %I:%M:%S %p",
        "%H:%M:%S",
    ],
)
def test_text_time_stamps_read_as_seconds_from_the_first_row(tmp_path, frame, plain, form):
    path = tmp_path / "stamped.csv"
    stamped(frame, form).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS)
    same_run(run, plain, time=False)
    # the run (8 h 20 min from 22:00) passes midnight: a time of day alone counts on into the next day
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], rtol=0, atol=1e-9)


def test_iso_stamps_with_a_utc_offset_cross_a_clock_change_evenly(tmp_path):
    # Central Europe changes to summer time at 01:00 UTC on 2026-03-29: the local stamps jump an hour, the
    # offsets say why, and the samples stay a minute apart
    utc = pd.date_range("2026-03-29 00:30", periods=90, freq="60s", tz="UTC")
    local = utc.tz_convert("Europe/Berlin")
    column = pd.Series([t.isoformat() for t in local])
    assert column.str.contains(r"\+02:00").any() and column.str.contains(r"\+01:00").any()
    np.testing.assert_array_equal(text_seconds(column, "time", "run.csv"), 60.0 * np.arange(90))


@pytest.mark.parametrize(
    "dates",
    [
        ("01/03/2026", "02/03/2026"),  # day first: 1 → 2 March (month first, 3 January → 3 February)
        ("03/01/2026", "03/02/2026"),  # month first: 1 → 2 March (day first, 3 January → 3 February)
    ],
)
def test_day_and_month_are_told_apart_by_the_even_sampling(dates):
    before, after = dates
    column = pd.Series([f"{before} 23:59:00", f"{after} 00:00:40", f"{after} 00:02:20", f"{after} 00:04:00"])
    np.testing.assert_array_equal(text_seconds(column, "t", "run.csv"), [0.0, 100.0, 200.0, 300.0])


def test_a_time_stamp_that_is_no_date_is_named_with_its_row(tmp_path, frame):
    path = tmp_path / "stamped.csv"
    broken = stamped(frame, "%d.%m.%Y %H:%M:%S")
    broken.loc[4, "time_s"] = "ERR"
    broken.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"row 5, column 'time_s': 'ERR' is not a date-time in the form of the"):
        load_run(path, temps=TEMPS)
    broken.loc[0, "time_s"] = "Monday"
    broken.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"row 1, column 'time_s': 'Monday' is neither a number of seconds nor"):
        load_run(path, temps=TEMPS)


def test_a_fit_on_a_logger_table_equals_the_fit_on_the_plain_one(tmp_path, frame, capsys):
    path = tmp_path / "logger.csv"
    body = stamped(frame, "%d.%m.%Y %H:%M:%S").to_csv(index=False, sep=";", decimal=",")
    path.write_bytes(("Logger\n" + body).encode("cp1252"))
    models = {}
    for name, data in (("plain", SYNTHETIC), ("logger", path)):
        out = tmp_path / name
        args = ["fit", "--data", str(data), "--temps", ",".join(TEMPS), "--p", "1", "--search", "exact"]
        assert main([*args, "--out", str(out), "--recalibrate", "none", "--quiet"]) == 0
        models[name] = (out / "model.json").read_text()
    capsys.readouterr()
    plain_model, logger_model = (json.loads(models[k]) for k in ("plain", "logger"))
    assert plain_model["breaks"] == logger_model["breaks"]
    np.testing.assert_array_equal(np.asarray(plain_model["coefficients"]), np.asarray(logger_model["coefficients"]))


def test_a_workbook_with_a_units_row_and_text_time_stamps(tmp_path, frame, plain):
    stamps = stamped(frame, "%d.%m.%Y %H:%M:%S")
    units = pd.DataFrame([{c: ("" if c == "time_s" else "°C") for c in frame.columns}])
    path = tmp_path / "logger.xlsx"
    pd.concat([units, stamps.astype(object)], ignore_index=True).to_excel(path, index=False)
    run = load_run(path, temps=TEMPS)
    same_run(run, plain, time=False)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], rtol=0, atol=1e-9)


def test_resampling_takes_a_broken_sensors_readings_as_missed_and_interpolates_them(tmp_path, frame):
    path = tmp_path / "broken.csv"
    broken = frame.copy()
    broken.loc[40:41, "T3"] = -999.0  # a thermocouple off its input for two readings
    broken.loc[70, "T1"] = 9999.0  # an overflow
    broken.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"row 71, column 'T1': 9999 °C .* or take such readings as missed with"):
        load_run(path, temps=TEMPS)
    run = load_run(path, temps=TEMPS, resample=100.0)
    expected = frame[TEMPS].to_numpy(dtype=float).copy()
    expected[40:42, 2] = np.interp([40, 41], [39, 42], expected[[39, 42], 2])  # straight across, as for empty cells
    expected[70, 0] = 0.5 * (expected[69, 0] + expected[71, 0])
    np.testing.assert_allclose(run.temps, expected, rtol=0, atol=1e-9)
    assert any("outside the plausible range taken as missed (1 in 'T1', 2 in 'T3')" in note for note in run.notes)
    np.testing.assert_array_equal(run.frame["spindle_on"], frame["spindle_on"])  # not an input: left as it is


@pytest.mark.parametrize(
    "mark",
    ["---", "-", "n.a.", "OVL", "Err", "*", "Err.", "OL", "#N/A", "#NV", "#VALUE!", "#DIV/0!", "1.#INF", "1.#QNAN"],
)
def test_a_cell_marking_a_reading_not_taken_is_an_empty_cell(tmp_path, frame, plain, mark):
    path = tmp_path / "marked.csv"
    marked = frame.astype(object)
    marked.loc[marked.index % 4 != 0, "error_um"] = mark  # the error measured on one row in four
    marked.to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, missing_error=True)
    expected = plain.error.copy()
    expected[np.arange(len(expected)) % 4 != 0] = np.nan
    np.testing.assert_array_equal(run.error, expected)
    marked.loc[:, "error_um"] = frame["error_um"]
    marked.loc[30, "T2"] = mark
    marked.to_csv(path, index=False)
    said = "empty" if mark in ("#N/A", "1.#QNAN") else f"{re.escape(repr(mark))} \\(no reading\\)"  # pandas' NaN
    with pytest.raises(InputError, match=rf"row 31, column 'T2' is {said}"):
        load_run(path, temps=TEMPS)
    np.testing.assert_allclose(load_run(path, temps=TEMPS, resample=100.0).temps[30, 1], plain.temps[29:32:2, 1].mean())


@pytest.mark.parametrize("decimal", [".", ","])
def test_a_table_separated_by_runs_of_spaces_is_read(tmp_path, frame, plain, decimal):
    path = tmp_path / "lab.dat"
    aligned = frame.to_string(index=False, float_format=lambda v: repr(float(v)))  # right-aligned columns
    text = "Lab logger 3 export\n\n" + (aligned.replace(".", ",") if decimal == "," else aligned) + "\n"
    path.write_text(text)
    same_run(load_run(path, temps=TEMPS), plain)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be", "utf-32"])
def test_a_unicode_text_export_is_read_by_its_byte_order_mark(tmp_path, frame, plain, encoding):
    path = tmp_path / "unicode.txt"
    frame.rename(columns={"T1": "T1 [°C]"}).to_csv(path, sep="\t", index=False, encoding=encoding)
    if encoding == "utf-16-be":
        path.write_bytes(codecs.BOM_UTF16_BE + path.read_bytes())
    run = load_run(path, temps=["T1 [°C]", *TEMPS[1:]])
    same_run(run, plain)


@pytest.mark.parametrize("suffix", [".gz", ".bz2", ".xz", ".zip"])
def test_a_compressed_table_is_read_as_the_table_it_holds(tmp_path, frame, plain, suffix):
    text = frame.to_csv(index=False).encode()
    path = tmp_path / f"log.csv{suffix}" if suffix != ".zip" else tmp_path / "log.zip"
    if suffix == ".zip":
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr("log.csv", text)
    else:
        path.write_bytes({".gz": gzip.compress, ".bz2": bz2.compress, ".xz": lzma.compress}[suffix](text))
    run = load_run(path, temps=TEMPS)
    same_run(run, plain)
    assert run.name == "log"


def test_an_archive_of_several_files_or_a_broken_one_is_refused_in_one_line(tmp_path, frame):
    several = tmp_path / "logs.zip"
    with zipfile.ZipFile(several, "w") as archive:
        archive.writestr("a.csv", frame.to_csv(index=False))
        archive.writestr("b.csv", frame.to_csv(index=False))
    with pytest.raises(InputError, match=r"logs.zip: a zip archive of one table is read; this one holds a.csv, b.csv"):
        load_run(several, temps=TEMPS)
    broken = tmp_path / "log.csv.gz"
    broken.write_bytes(b"not compressed")
    with pytest.raises(InputError, match=r"log.csv.gz: not a readable CSV table"):
        load_run(broken, temps=TEMPS)


@pytest.mark.parametrize("name", ["Date", "Datum/Zeit", "DateTime"])
def test_a_date_column_of_spreadsheet_serial_days_is_read_in_seconds(tmp_path, frame, plain, name):
    path = tmp_path / "serial.csv"
    days = 46083.25 + (frame["time_s"] - frame["time_s"].iloc[0]) / 86400.0  # 2026-03-02 06:00 on
    frame.drop(columns="time_s").assign(**{name: days}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time=name)
    same_run(run, plain, time=False)
    np.testing.assert_allclose(run.time - run.time[0], plain.time - plain.time[0], rtol=0, atol=1e-5)
    assert run.period == pytest.approx(plain.period, rel=1e-9)
    assert any("holds spreadsheet serial dates (days since 1899-12-30)" in note for note in run.notes)
    assert not any("jitter" in note for note in run.notes)  # a float's rounding of days is no clock jitter


@pytest.mark.parametrize("per_second", [1e3, 1e6, 1e9])
def test_unix_times_in_ms_us_or_ns_are_read_in_seconds_unless_the_name_says_seconds(tmp_path, frame, plain, per_second):
    path = tmp_path / "epoch.csv"
    stamps = (1.77e9 + frame["time_s"]) * per_second
    frame.drop(columns="time_s").assign(timestamp=stamps).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time="timestamp")
    same_run(run, plain, time=False)
    np.testing.assert_allclose(run.time - run.time[0], plain.time - plain.time[0], rtol=0, atol=1e-3)
    assert any("holds Unix times in" in note for note in run.notes)
    named = tmp_path / "named.csv"
    frame.assign(time_s=stamps).to_csv(named, index=False)
    with pytest.raises(InputError, match="is not a plausible time"):
        load_run(named, temps=TEMPS)


def test_windows_file_times_are_read_in_seconds(tmp_path, frame, plain):
    path = tmp_path / "filetime.csv"
    unix = 1.77e9 + frame["time_s"].to_numpy()
    stamps = np.round((unix + 11644473600.0) * 1e7).astype(np.int64)  # 100 ns ticks since 1601-01-01
    frame.drop(columns="time_s").assign(timestamp=stamps).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time="timestamp")
    same_run(run, plain, time=False)
    np.testing.assert_allclose(run.time - run.time[0], plain.time - plain.time[0], rtol=0, atol=1e-5)
    assert any("holds Windows file times (100 ns since 1601)" in note for note in run.notes)


def test_numbers_in_the_serial_range_are_seconds_unless_the_column_is_named_as_a_date(tmp_path, frame, plain):
    path = tmp_path / "elapsed.csv"
    seconds = 30000.0 + (frame["time_s"] - frame["time_s"].iloc[0]) / 1000.0  # elapsed s, sampled every 0.1 s
    frame.drop(columns="time_s").assign(Elapsed=seconds).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time="Elapsed")
    assert run.period == pytest.approx(0.1, rel=1e-9)
    in_days = tmp_path / "days.csv"
    frame.assign(time_s=frame["time_s"] / 86400.0).rename(columns={"time_s": "time [d]"}).to_csv(in_days, index=False)
    assert load_run(in_days, temps=TEMPS, time="time [d]").period == pytest.approx(plain.period, rel=1e-9)


def test_a_workbook_is_read_from_its_largest_table_of_numbers_past_a_cover_and_a_constants_sheet(
    tmp_path, frame, plain
):
    path = tmp_path / "export.xlsx"
    with pd.ExcelWriter(path) as workbook:
        pd.DataFrame({"Logger": ["XYZ 2000", "machine 7", "operator A"]}).to_excel(
            workbook, sheet_name="Info", index=False
        )
        calibration = pd.DataFrame({"sensor": [1, 2, 3, 4], "offset_K": [0.1, -0.05, 0.02, 0.0]})
        calibration.to_excel(workbook, sheet_name="Calibration", index=False)  # numbers, but not the log
        frame.to_excel(workbook, sheet_name="Data", index=False)
        frame.head(3).to_excel(workbook, sheet_name="Later", index=False)  # a smaller table is not read
    run = load_run(path, temps=TEMPS)
    same_run(run, plain)
    assert run.source == f"{path} (sheet 'Data')"
    with pytest.raises(InputError, match=r"export.xlsx \(sheet 'Data'\): column 'T9' not found"):
        load_run(path, temps=["T9"])
    covers = tmp_path / "covers.xlsx"
    with pd.ExcelWriter(covers) as workbook:
        pd.DataFrame({"Logger": ["XYZ 2000"]}).to_excel(workbook, sheet_name="Info", index=False)
    with pytest.raises(InputError, match=r"covers.xlsx: column 'time_s' not found"):  # no table: the first sheet
        load_run(covers, temps=TEMPS)


def test_a_workbook_with_a_title_and_a_preamble_above_its_header_reads_as_the_plain_run(tmp_path, frame, plain):
    path = tmp_path / "titled.xlsx"
    with pd.ExcelWriter(path) as workbook:
        head = pd.DataFrame(
            [["Thermal test, machine 7", None], [None, None], ["Start", "2026-03-02 08:00"], ["Operator", "A"]]
        )
        head.to_excel(workbook, sheet_name="Log", index=False, header=False)
        frame.to_excel(workbook, sheet_name="Log", index=False, startrow=len(head) + 1)
    same_run(load_run(path, temps=TEMPS), plain)
    twice = tmp_path / "twice.xlsx"
    with pd.ExcelWriter(twice) as workbook:
        head.to_excel(workbook, sheet_name="Log", index=False, header=False)
        frame.rename(columns={"T2": "T1"}).to_excel(workbook, sheet_name="Log", index=False, startrow=len(head) + 1)
    with pytest.raises(InputError, match=r"twice.xlsx: column 'T1' appears twice \(columns 2 and 3\)"):
        load_run(twice, temps=TEMPS)


@pytest.mark.parametrize("name, per_second", [("time_ms", 1000.0), ("Zeit [min]", 1 / 60), ("hours", 1 / 3600)])
def test_a_time_column_named_with_its_unit_is_read_in_seconds(tmp_path, frame, plain, name, per_second):
    path = tmp_path / "units.csv"
    frame.assign(time_s=frame["time_s"] * per_second).rename(columns={"time_s": name}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time=name)
    same_run(run, plain, time=False)
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)
    assert run.period == pytest.approx(plain.period, rel=1e-12)


def test_a_model_fitted_on_minutes_replays_on_minutes_as_the_one_on_seconds(tmp_path, frame, capsys):
    minutes = tmp_path / "minutes.csv"
    frame.assign(time_s=frame["time_s"] / 60).rename(columns={"time_s": "t_min"}).to_csv(minutes, index=False)
    args = ["--temps", ",".join(TEMPS), "--p", "1", "--search", "exact", "--recalibrate", "none", "--quiet"]
    replays = {}
    for name, data, time in (("seconds", SYNTHETIC, "time_s"), ("minutes", minutes, "t_min")):
        out = tmp_path / name
        assert main(["fit", "--data", str(data), "--time", time, *args, "--out", str(out)]) == 0
        assert json.loads((out / "model.json").read_text())["sampling_period_s"] == pytest.approx(100.0)
        replay = ["replay", str(out / "model.json"), "--data", str(data), "--json", str(out / "replay.json")]
        assert main(replay) == 0
        replays[name] = json.loads((out / "replay.json").read_text())
    capsys.readouterr()
    on_minutes, on_seconds = replays["minutes"]["samples"], replays["seconds"]["samples"]
    assert [{**r, "time_s": None} for r in on_minutes] == [{**r, "time_s": None} for r in on_seconds]
    np.testing.assert_allclose([r["time_s"] for r in on_minutes], [r["time_s"] for r in on_seconds], rtol=1e-12)
    assert replays["minutes"]["rms_um"] == replays["seconds"]["rms_um"]


def test_a_restarted_clock_is_told_from_rows_out_of_order(frame):
    restarted = frame.copy()
    restarted.loc[150:, "time_s"] -= restarted.loc[150, "time_s"]  # the logger powered up again at row 151
    with pytest.raises(InputError, match=r"starts again at row 151 \(0 s after 15000 s.*split the file before row"):
        load_run(restarted, temps=TEMPS, name="restarted.csv")
    swapped = frame.copy()
    swapped.loc[[150, 151], "time_s"] = swapped.loc[[151, 150], "time_s"].to_numpy()  # two rows out of order
    with pytest.raises(InputError, match=r"not strictly increasing at row 152 .*sort the rows"):
        load_run(swapped, temps=TEMPS, name="swapped.csv")
    bad_cell = frame.copy()
    bad_cell.loc[150, "time_s"] = 0.0  # one corrupt stamp; the clock goes on as before
    with pytest.raises(InputError, match=r"not strictly increasing at row 151 .*sort the rows"):
        load_run(bad_cell, temps=TEMPS, name="bad_cell.csv")


@pytest.mark.parametrize(
    "names, time_like",
    [
        (["Date", "Time", "T1", "T_amb", "T_1", "temp", "Times", "time2", "timer_on"], ["Date", "Time"]),
        (["Timestamp", "Date/Time", "DateTime", "Date_Time", "time-stamp", "Time (UTC)"], None),
        (["Zeit [min]", "Datum", "Uhrzeit", "elapsed_h", "t", "t_s", "t [min]", "t_ambient", "t_1"], None),
    ],
)
def test_the_names_a_logger_gives_its_time_column_and_not_its_sensors(names, time_like):
    expected = time_like if time_like is not None else [n for n in names if n not in ("t_ambient", "t_1")]
    assert time_like_columns(names) == expected


def split_stamps(frame):
    """The run with a date column and a time-of-day column instead of seconds, from 22:00 over midnight."""
    stamps = stamped(frame, "%d.%m.%Y %H:%M:%S")["time_s"].str.split(" ", expand=True)
    return frame.drop(columns="time_s").assign(Date=stamps[0], Time=stamps[1])[["Date", "Time", *TEMPS, "error_um"]]


def test_a_log_without_time_s_is_read_on_the_column_named_as_its_time(tmp_path, frame, plain):
    path = tmp_path / "split.csv"
    split_stamps(frame).to_csv(path, index=False, sep=";")
    run = load_run(path, temps=TEMPS)  # the date and the time of day beside it read as one stamp
    assert run.time_name == "Date Time" and "time from columns 'Date' and 'Time'" in run.notes[0]
    same_run(run, plain, time=False)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], rtol=0, atol=1e-9)
    named = frame.rename(columns={"time_s": "t [min]"}).assign(**{"t [min]": frame["time_s"] / 60})
    same_run(load_run(named, temps=TEMPS, name="minutes.csv"), plain, time=False)


def test_only_the_default_time_column_is_looked_for_and_a_bad_stamp_still_named(tmp_path, frame):
    split = split_stamps(frame)
    with pytest.raises(InputError, match=r"column 'Clock' not found"):  # a column asked for is never replaced
        load_run(split, temps=TEMPS, time="Clock", name="split.csv")
    unnamed = split.drop(columns="Date").rename(columns={"Time": "Clock"})
    with pytest.raises(
        InputError,
        match=r"column 'time_s' not found \(name the time column with --time COLUMN\); the columns are: Clock, T1",
    ):
        load_run(unnamed, temps=TEMPS, name="unnamed.csv")
    split.loc[4, "Time"] = "ERR"
    with pytest.raises(InputError, match=r"row 5, column 'Time': 'ERR' is not a date-time"):
        load_run(split.drop(columns="Date"), temps=TEMPS, name="broken.csv")


def test_a_model_fitted_on_a_split_stamped_log_replays_it_as_the_plain_model_replays_the_plain_run(tmp_path, frame):
    split = tmp_path / "split.csv"
    split_stamps(frame).to_csv(split, index=False)
    args = ["--temps", ",".join(TEMPS), "--p", "1", "--search", "exact", "--recalibrate", "none", "--quiet"]
    replays = {}
    for name, data in (("plain", SYNTHETIC), ("split", split)):
        out = tmp_path / name
        assert main(["fit", "--data", str(data), *args, "--out", str(out)]) == 0
        replay = ["replay", str(out / "model.json"), "--data", str(data), "--json", str(out / "replay.json")]
        assert main(replay) == 0
        replays[name] = json.loads((out / "replay.json").read_text())
    assert json.loads((tmp_path / "split" / "model.json").read_text())["training"]["time"] == "Date Time"
    on_split, on_plain = replays["split"]["samples"], replays["plain"]["samples"]
    assert [{**r, "time_s": None} for r in on_split] == [{**r, "time_s": None} for r in on_plain]
    assert replays["split"]["rms_um"] == replays["plain"]["rms_um"]


@pytest.mark.parametrize("sep, decimal", [(",", "."), (";", ",")])
def test_a_footer_after_the_last_row_of_data_is_not_read(tmp_path, frame, plain, sep, decimal):
    path = tmp_path / "footer.csv"
    footer = f"\n\nLogging stopped at 04:00{sep}{sep}\nEND{sep * (len(frame.columns) + 2)}\n"
    path.write_text(frame.to_csv(index=False, sep=sep, decimal=decimal) + footer)
    same_run(load_run(path, temps=TEMPS), plain)
    sheet = tmp_path / "footer.xlsx"
    pd.concat([frame.astype(object), pd.DataFrame([{"time_s": "Logging stopped"}])], ignore_index=True).to_excel(
        sheet, index=False
    )
    same_run(load_run(sheet, temps=TEMPS), plain)


@pytest.mark.parametrize("sep, decimal", [(",", "."), (";", ",")])
@pytest.mark.parametrize(
    "labels", [("Max", "Min", "Avg"), ("Maximum:", "Minimum:", "Mittelwert:", "P-P"), ("Std.Abw.", "Spanne", "Varianz")]
)
def test_rows_of_statistics_under_the_readings_are_a_footer_and_not_read(tmp_path, frame, plain, sep, decimal, labels):
    readings = frame.drop(columns="time_s")
    statistics = pd.DataFrame(
        [[label, *readings.agg(how)] for label, how in zip(labels, ("max", "min", "mean", "std"))],
        columns=frame.columns,
    )
    table = pd.concat([frame.astype(object), statistics], ignore_index=True)
    path = tmp_path / "statistics.csv"
    path.write_text(table.to_csv(index=False, sep=sep, decimal=decimal) + f"Logging stopped{sep}\n")
    same_run(load_run(path, temps=TEMPS), plain)
    sheet = tmp_path / "statistics.xlsx"
    table.to_excel(sheet, index=False)
    same_run(load_run(sheet, temps=TEMPS), plain)


def test_a_row_of_statistics_between_rows_of_data_is_still_refused_with_its_row(tmp_path, frame):
    path = tmp_path / "middle.csv"
    lines = frame.to_csv(index=False).splitlines()
    lines.insert(11, "Max," + ",".join(["25.0"] * (len(frame.columns) - 1)))
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"row 11, column 'time_s': 'Max' is not a number"):
        load_run(path, temps=TEMPS)


def test_text_between_rows_of_data_is_still_refused_with_its_row(tmp_path, frame):
    path = tmp_path / "middle.csv"
    lines = frame.to_csv(index=False).splitlines()
    lines.insert(11, "Logging paused at 08:15")  # the header is line 0: this is data row 11
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"row 11, column 'time_s': 'Logging paused at 08:15' is not a number"):
        load_run(path, temps=TEMPS)


def test_the_names_a_log_gives_its_thermal_error():
    names = ["dZ_um", "Abweichung [µm]", "drift", "deltaZ", "dx", "Fehler", "x (um)", "T1", "delta_T", "errand", "dt"]
    assert error_like_columns(names) == names[:7]


def test_a_log_without_error_um_is_read_on_its_one_error_column(tmp_path, frame, plain, capsys):
    renamed = frame.rename(columns={"time_s": "Zeit [s]", "error_um": "dZ [µm]"})
    run = load_run(renamed, temps=TEMPS, name="renamed.csv")
    assert (run.time_name, run.error_name) == ("Zeit [s]", "dZ [µm]")
    assert "thermal error from column 'dZ [µm]'" in run.notes[1]
    same_run(run, plain)
    assert load_run(renamed, temps=TEMPS, error=None, name="renamed.csv").error is None  # no error asked for
    probes = renamed.assign(**{"dX [µm]": renamed["dZ [µm]"] / 2})
    with pytest.raises(InputError, match=r"2 could be the thermal error \(dZ \[µm\], dX \[µm\]\); name it with --e"):
        load_run(probes, temps=TEMPS, name="probes.csv")
    same_run(load_run(probes, temps=TEMPS, error="dZ [µm]", name="probes.csv"), plain, time=True)
    # a replay, which runs without an error too, never takes another column for it
    assert load_run(probes, temps=TEMPS, require_error=False, name="probes.csv").error is None


def test_inputs_named_as_temperatures_are_taken_when_none_is_named_like_a_sensor(frame, plain):
    named = {"T1": "Spindle [°C]", "T2": "Temp2", "T3": "TC3", "T4": "bed_degC"}
    run = load_run(frame.rename(columns=named).assign(**{"Ambient [°C]": 20.0 + frame["T1"] / 10}), name="named.csv")
    assert run.temp_names == tuple(named.values())  # in table order, the ambient left out
    same_run(run, plain)
    both = frame.assign(**{"Spindle [°C]": frame["T1"]})
    assert load_run(both, name="both.csv").temp_names == tuple(TEMPS)  # sensors named T1 … win


def test_a_sweep_excludes_the_time_and_error_columns_it_found(tmp_path, frame):
    renamed = frame.rename(columns={"time_s": "Zeit [s]", "error_um": "dZ [µm]", "T1": "Spindle [°C]"})
    renamed.to_csv(tmp_path / "renamed.csv", index=False, sep=";", decimal=",")
    (everything,) = read_datasets({"path": "renamed.csv", "temps": ["*"]}, tmp_path, "study.toml")
    assert everything.candidates[:4] == ("Spindle [°C]", "T2", "T3", "T4")
    assert not {"Zeit [s]", "dZ [µm]"} & set(everything.candidates)  # the time and the error are no candidates
    (default,) = read_datasets({"path": "renamed.csv"}, tmp_path, "study.toml")
    assert default.candidates == ("T2", "T3", "T4")  # named like sensors: those win


def test_an_axis_drift_and_a_temperature_word_anywhere_are_recognised():
    assert error_like_columns(["Z drift", "z_error", "X-Deviation", "x_errand", "T1", "Zone", "delta_T"]) == [
        "Z drift",
        "z_error",
        "X-Deviation",
    ]
    names = ["Time", "Spindle_Temp", "Motor temp", "Tempo", "attempt", "Ambient temp", "Z drift"]
    assert default_temperature_columns(names) == ["Spindle_Temp", "Motor temp"]


@pytest.mark.parametrize("suffix", [".xlsx", ".csv"])
def test_a_date_column_or_a_unix_stamp_beside_the_time_fits_the_model_of_the_plain_run(tmp_path, frame, suffix):
    """Columns no input can be derived from (a date, a Unix time, a counter beyond the rule's limit) are kept
    out of the model's source ranges; the model file they once made invalid fits and diagnoses."""
    stamps = pd.Timestamp("2026-03-02 20:00:00") + pd.to_timedelta(frame["time_s"] - frame["time_s"][0], unit="s")
    extra = frame.assign(Date=stamps.dt.normalize(), Unix=1.77e9 + frame["time_s"], Counter=1e13 + frame["time_s"])
    path = tmp_path / f"log{suffix}"
    if suffix == ".xlsx":
        extra.to_excel(path, index=False)
    else:
        extra.assign(Date=stamps.dt.strftime("%Y-%m-%d")).to_csv(path, index=False)
    args = ["--temps", ",".join(TEMPS), "--p", "1", "--search", "exact", "--recalibrate", "none", "--quiet"]
    models = {}
    for name, data in (("plain", SYNTHETIC), ("extra", path)):
        assert main(["fit", "--data", str(data), *args, "--out", str(tmp_path / name)]) == 0
        models[name] = json.loads((tmp_path / name / "model.json").read_text())
    assert models["extra"]["coefficients"] == models["plain"]["coefficients"]
    ranges = models["extra"]["switching"]["source_ranges"]
    assert "T1" in ranges and not {"Date", "Unix", "Counter"} & set(ranges)
    diagnosed = ["diagnose", str(tmp_path / "extra" / "model.json"), "--data", str(path)]
    assert main([*diagnosed, "--out", str(tmp_path / "diagnose")]) == 0


def test_numbers_stored_as_text_with_a_comma_in_a_sheet_are_read_where_the_comma_says_what_it_is(
    tmp_path, frame, plain
):
    sheet = tmp_path / "text.xlsx"
    written = frame.astype(object).assign(
        T1=[f"{v:.2f}".replace(".", ",") for v in frame["T1"]],  # 20,5: a decimal comma
        T2=[f"{v:.4f}" for v in frame["T2"]],  # a decimal point
        note=["a, b"] + [""] * (len(frame) - 1),  # words with a comma stay words
    )
    written.to_excel(sheet, index=False)
    run = load_run(sheet, temps=TEMPS)
    np.testing.assert_allclose(run.temps, plain.temps, atol=5e-3)
    np.testing.assert_array_equal(run.error, plain.error)
    written.assign(T1=[f"{1000 * v:,.1f}" for v in frame["T1"]]).to_excel(sheet, index=False)  # 20,512.3
    np.testing.assert_allclose(
        load_run(sheet, temps=TEMPS, check_ranges=False).temps[:, 0], 1000 * plain.temps[:, 0], atol=0.05
    )


def test_numbers_stored_as_text_whose_comma_may_be_either_are_refused_naming_the_column(tmp_path, frame):
    sheet = tmp_path / "text.xlsx"
    frame.astype(object).assign(T3=[f"{v:.3f}".replace(".", ",") for v in frame["T3"]]).to_excel(sheet, index=False)
    with pytest.raises(InputError, match=r"text.xlsx: .*column 'T3' holds numbers as text, such as '\d+,\d{3}'"):
        load_run(sheet, temps=TEMPS)


def test_the_air_is_told_by_its_word_not_by_three_letters_inside_another():
    ambient = ("T_amb", "Tamb", "tamb_C", "Ambient [°C]", "AMB_TEMP", "Room", "chamber_t", "Chamber [°C]", "Enclosure")
    assert all(is_ambient_name(name) for name in ambient)
    assert not any(is_ambient_name(name) for name in ("lambda_1", "camber_T", "T1", "frame_t", "gamba_temp"))
    columns = ["time", "frame_t", "chamber_t", "bed_t", "he_t", "lambda_temp"]
    assert default_temperature_columns(columns) == ["lambda_temp"]  # the one named as a temperature
