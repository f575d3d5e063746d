"""A log of spreadsheet serial date-times (days since 1899-12-30, in a CSV or a workbook) or MATLAB datenums,
stamped in local wall-clock time across a change to or from summer time, reads as the same log stamped in text
and as pandas places the stamps in the zone: the same seconds, clock fields, columns and readings."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.clocks import cli, needs_zones

from groupfit.data import load_run

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
ROWS = 120
SPREADSHEET_EPOCH = pd.Timestamp("1899-12-30")
DATENUM_OFFSET_DAYS = 693960.0
CHANGES = {
    "berlin_back": ("Europe/Berlin", "2026-10-25 00:00:00"),  # 03:00 back to 02:00
    "berlin_ahead": ("Europe/Berlin", "2026-03-29 00:00:00"),  # 02:00 ahead to 03:00
    "new_york_back": ("America/New_York", "2026-11-01 05:00:00"),  # 02:00 back to 01:00
}
WRITTEN = {
    "csv as a spreadsheet saves it": ("log.csv", "%.10f", 0.0),
    "csv to six decimals": ("log.csv", "%.6f", 0.0),
    "workbook": ("log.xlsx", None, 0.0),
    "MATLAB datenums": ("log.csv", "%.10f", DATENUM_OFFSET_DAYS),
    "csv to four decimals": ("log.csv", "%.4f", 0.0),
}
"""How the numbers are written: the file, the CSV's number form, and the days added to a serial date."""

pytestmark = needs_zones


def wall_clock(zone: str, utc_start: str, period_s: float = 100.0) -> tuple[pd.DataFrame, pd.Series]:
    """The FE paper cycle's first rows without their time, and stamps every ``period_s`` in ``zone``'s wall-clock
    time."""
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:ROWS]
    utc = pd.Series(pd.Timestamp(utc_start, tz="UTC") + pd.to_timedelta(period_s * np.arange(ROWS), unit="s"))
    return log.drop(columns="time_s"), utc.dt.tz_convert(zone).dt.tz_localize(None)


def written(folder: Path, log: pd.DataFrame, stamps: pd.Series, how: str) -> Path:
    """The log with its stamps as serial days in a column ``Date`` written ``how`` (:data:`WRITTEN`)."""
    name, form, offset = WRITTEN[how]
    days = (stamps - SPREADSHEET_EPOCH) / pd.Timedelta(days=1) + offset
    table = pd.concat([pd.DataFrame({"Date": days}), log], axis=1)
    path = folder / "serial" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".xlsx":
        table.to_excel(path, index=False)
    else:
        table.to_csv(path, index=False, float_format=form)
    return path


def as_text(folder: Path, log: pd.DataFrame, stamps: pd.Series) -> Path:
    """The same log stamped in text, ``2026-10-25 02:30:00``."""
    path = folder / "text" / "log.csv"
    path.parent.mkdir(parents=True)
    pd.concat([pd.DataFrame({"Date": stamps.dt.strftime("%Y-%m-%d %H:%M:%S")}), log], axis=1).to_csv(path, index=False)
    return path


@pytest.mark.parametrize("how", sorted(set(WRITTEN) - {"csv to four decimals"}))
@pytest.mark.parametrize("change", sorted(CHANGES))
def test_serial_dates_across_a_change_of_summer_time_read_as_text_stamps_and_as_pandas_places_them(
    tmp_path, change, how
):
    zone, utc_start = CHANGES[change]
    log, stamps = wall_clock(zone, utc_start)
    serial, text = written(tmp_path, log, stamps, how), as_text(tmp_path, log, stamps)
    run, stamped = load_run(serial, time="Date"), load_run(text, time="Date")
    placed = pd.to_datetime(pd.read_csv(text)["Date"]).dt.tz_localize(zone, ambiguous="infer")
    seconds = (placed - placed.iloc[0]).dt.total_seconds().to_numpy()
    shift = (placed.iloc[-1].utcoffset() - placed.iloc[0].utcoffset()).total_seconds()
    np.testing.assert_array_equal(run.time, seconds)
    np.testing.assert_array_equal(run.time, stamped.time)
    origin = (placed.iloc[0].tz_localize(None) + pd.Timedelta(seconds=shift)).timestamp()
    assert (run.clock_origin_s, run.clock_shift_s) == (stamped.clock_origin_s, stamped.clock_shift_s) == (origin, shift)
    assert run.period == stamped.period and run.time_name == stamped.time_name == "Date"
    assert run.temp_names == stamped.temp_names and list(run.frame.columns) == list(stamped.frame.columns)
    np.testing.assert_array_equal(run.temps, stamped.temps)
    np.testing.assert_array_equal(run.error, stamped.error)
    datenums = WRITTEN[how][2] == DATENUM_OFFSET_DAYS
    kind = "MATLAB datenums (days since the year 0)" if datenums else "spreadsheet serial dates (days since 1899-12-30)"
    assert run.notes[0] == f"{serial}: column 'Date' holds {kind}: read in seconds"
    assert [note.replace(str(serial), str(text)) for note in run.notes[1:]] == list(stamped.notes)
    assert "summer time" in stamped.notes[0]


def test_serial_dates_to_four_decimals_on_whole_minutes_read_as_the_minutes_they_stand_for(tmp_path):
    """``46320.0833`` is 01:59:57 to the second, but no more than the 8.6 s a fourth decimal of a day tells apart:
    a log every five minutes reads on its whole minutes, and the stamp of 02:00 where the clock went back is not
    taken for one before it."""
    log, stamps = wall_clock("Europe/Berlin", "2026-10-24 23:00:00", period_s=300.0)
    serial, text = written(tmp_path, log, stamps, "csv to four decimals"), as_text(tmp_path, log, stamps)
    assert pd.read_csv(serial)["Date"].astype(str).str.len().max() == len("46320.0833")
    run, stamped = load_run(serial, time="Date"), load_run(text, time="Date")
    np.testing.assert_array_equal(run.time, stamped.time)
    assert (run.clock_origin_s, run.clock_shift_s) == (stamped.clock_origin_s, stamped.clock_shift_s)
    assert run.clock_shift_s == -3600.0 and run.period == 300.0


def test_serial_dates_without_a_change_read_as_text_stamps_and_an_hour_missed_is_still_a_gap(tmp_path, capsys):
    log, stamps = wall_clock("Europe/Berlin", "2026-06-10 11:00:00")
    serial, text = written(tmp_path, log, stamps, "csv as a spreadsheet saves it"), as_text(tmp_path, log, stamps)
    run, stamped = load_run(serial, time="Date"), load_run(text, time="Date")
    np.testing.assert_allclose(run.time - run.time[0], stamped.time, rtol=0, atol=1e-5)
    assert run.period == pytest.approx(stamped.period, rel=1e-6)
    assert not any("summer time" in note for note in run.notes)
    gap = stamps + pd.to_timedelta(3600.0 * (np.arange(ROWS) >= 60), unit="s")
    missed = written(tmp_path / "gap", log, gap, "csv as a spreadsheet saves it")
    assert cli("fit", "--data", missed, "--time", "Date", "--p", "0", "--quiet", "--out", tmp_path / "m") == 2
    assert f"{3600 + run.period:g} s apart" in capsys.readouterr().err
