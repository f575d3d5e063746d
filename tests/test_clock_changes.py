"""A log stamped in local time without a UTC offset, across a change to or from summer time, is read through
the change: checked against the same log stamped with its offsets, and against pandas' own time zones."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.clocks import cli, needs_zones

from groupfit.clock_changes import read_through, summer_time_changes
from groupfit.data import load_runs

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
QUICK = ["--reference", "none", "--quiet", "--p", "0", "--ridge", "0", "--recalibrate", "none"]
CHANGES = [
    ("Europe/Berlin", "2026-10-25 00:00:00", -1),  # 03:00 back to 02:00
    ("Europe/Berlin", "2026-03-29 00:00:00", 1),  # 02:00 ahead to 03:00
    ("America/New_York", "2026-11-01 05:00:00", -1),  # 02:00 back to 01:00
    ("Australia/Sydney", "2026-04-04 15:00:00", -1),  # 03:00 back to 02:00, the southern autumn
    ("Australia/Sydney", "2026-10-03 15:00:00", 1),  # 02:00 ahead to 03:00
]

pytestmark = needs_zones


def stamped_logs(tmp_path: Path, zone: str, utc_start: str, rows: int = 120) -> tuple[Path, Path, int]:
    """The FE paper cycle's first rows stamped in ``zone``'s wall-clock time and with their UTC offsets, and
    the row (1-based) after the clock's change."""
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:rows]
    local = (pd.Timestamp(utc_start, tz="UTC") + pd.to_timedelta(log["time_s"], unit="s")).dt.tz_convert(zone)
    wall, offset = tmp_path / "wall.csv", tmp_path / "offset.csv"
    for path, stamps in ((wall, local.dt.strftime("%Y-%m-%d %H:%M:%S")), (offset, local.map(lambda t: t.isoformat()))):
        log.assign(time_s=stamps).rename(columns={"time_s": "Timestamp"}).to_csv(path, index=False)
    offsets = local.map(lambda t: t.utcoffset().total_seconds()).to_numpy()
    change = np.flatnonzero(np.diff(offsets))
    assert change.size == 1, "the stretch must hold one change of the clock"
    return wall, offset, int(change[0]) + 2


@pytest.mark.parametrize(("zone", "utc_start", "hours"), CHANGES)
def test_a_local_clock_changing_for_summer_time_reads_as_its_stamps_with_offsets(tmp_path, zone, utc_start, hours):
    wall, offset, change = stamped_logs(tmp_path, zone, utc_start)
    [local], [placed] = load_runs(wall, time="Timestamp"), load_runs(offset, time="Timestamp")
    assert np.array_equal(local.time, placed.time) and local.period == placed.period
    last_offset_s = pd.Timestamp(pd.read_csv(offset)["Timestamp"].iloc[-1]).utcoffset().total_seconds()
    assert local.clock_origin_s - placed.clock_origin_s == last_offset_s  # the first row in the last row's clock
    assert np.array_equal(local.error, placed.error)
    [note] = [n for n in local.notes if "summer time" in n]
    went = "ahead" if hours > 0 else "back"
    assert f"goes {went} an hour at row {change} " in note and zone in note
    assert not any("summer time" in n for n in placed.notes)


@pytest.mark.parametrize("resample", [[], ["--resample", "100"]])
def test_fit_on_a_log_across_the_end_of_summer_time_equals_the_fit_on_its_stamps_with_offsets(tmp_path, resample):
    wall, offset, change = stamped_logs(tmp_path, "Europe/Berlin", "2026-10-25 00:00:00")
    reports = []
    for path in (wall, offset):
        report = tmp_path / f"{path.stem}.json"
        assert cli("fit", "--data", path, "--time", "Timestamp", *QUICK, *resample, "--json", report) == 0
        reports.append(json.loads(report.read_text()))
    assert reports[0]["n_samples"] == reports[1]["n_samples"] == (120 if not resample else reports[1]["n_samples"])
    assert reports[0]["coefficients"] == reports[1]["coefficients"]


def test_an_hour_missed_where_no_clock_changes_is_still_a_gap(tmp_path, capsys):
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:120]
    period = float(log["time_s"].diff().median())
    seconds = log["time_s"].to_numpy(dtype=float) + 3600.0 * (np.arange(len(log)) >= 60)
    stamps = pd.Timestamp("2026-06-10 13:00:00") + pd.to_timedelta(seconds, unit="s")
    path = tmp_path / "gap.csv"
    log.assign(time_s=stamps.strftime("%Y-%m-%d %H:%M:%S")).to_csv(path, index=False)
    assert cli("fit", "--data", path, *QUICK, "--out", tmp_path / "m") == 2
    assert f"{3600 + period:g} s apart" in capsys.readouterr().err
    assert not (tmp_path / "m.json").exists()


def test_a_clock_going_back_an_hour_where_no_clock_changes_is_still_refused(tmp_path, capsys):
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:120]
    seconds = log["time_s"].to_numpy(dtype=float) - 3600.0 * (np.arange(len(log)) >= 60)
    stamps = pd.Timestamp("2026-06-10 13:00:00") + pd.to_timedelta(seconds, unit="s")
    path = tmp_path / "back.csv"
    log.assign(time_s=stamps.strftime("%Y-%m-%d %H:%M:%S")).to_csv(path, index=False)
    assert cli("fit", "--data", path, *QUICK, "--out", tmp_path / "m") == 2
    assert "goes back one hour at row 61" in capsys.readouterr().err


def test_a_naive_date_time_column_of_a_table_reads_through_the_change():
    utc = pd.date_range("2026-10-25 00:00", periods=300, freq="30s", tz="UTC")
    wall = utc.tz_convert("Europe/Paris").tz_localize(None)
    rng = np.random.default_rng(3)
    temp = 20.0 + np.cumsum(rng.normal(0.0, 0.01, len(utc)))
    frame = pd.DataFrame({"time": wall, "T1": temp, "error_um": 2.0 * (temp - 20.0)})
    [run] = load_runs(frame, time="time")
    assert np.array_equal(run.time, (utc - utc[0]).total_seconds().to_numpy())
    assert any("Europe/Paris" in n or "other zones" in n for n in run.notes)


@pytest.mark.parametrize("zone", ["Europe/London", "America/Chicago", "America/Santiago", "Pacific/Auckland"])
def test_the_changes_found_are_those_of_the_zone_as_pandas_converts_it(zone):
    """A year of 10 min samples in the zone's wall-clock time: read through its changes, every step is the
    period again, and each change found names the zone at the row where pandas' own offset changes."""
    utc = pd.date_range("2026-01-01", "2027-01-01", freq="10min", tz="UTC")
    local = utc.tz_convert(zone)
    wall = (local.tz_localize(None) - pd.Timestamp("1970-01-01")).total_seconds().to_numpy()
    changes = summer_time_changes(wall)
    offsets = np.array([t.utcoffset().total_seconds() for t in local])
    expected = np.flatnonzero(np.diff(offsets)) + 1
    assert [c.row for c in changes] == expected.tolist()
    assert all(zone in c.zones for c in changes)
    assert np.all(np.diff(read_through(wall, changes)) == 600.0)


def test_a_us_log_on_the_day_the_clock_goes_back_reads_its_date_as_month_first(tmp_path):
    """11/01/2026 reads as 1 November and as 11 January alike; only on 1 November does a clock go back, so the
    month comes first, as the same log stamped in ISO form reads."""
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:120]
    utc = pd.Timestamp("2026-11-01 05:00:00", tz="UTC") + pd.to_timedelta(log["time_s"], unit="s")
    local = utc.dt.tz_convert("America/New_York")
    us, iso = tmp_path / "us.csv", tmp_path / "iso.csv"
    for path, form in ((us, "%m/%d/%Y %I:%M:%S %p"), (iso, "%Y-%m-%d %H:%M:%S")):
        log.assign(time_s=local.dt.strftime(form)).rename(columns={"time_s": "Timestamp"}).to_csv(path, index=False)
    [month_first], [in_iso] = load_runs(us, time="Timestamp"), load_runs(iso, time="Timestamp")
    assert np.array_equal(month_first.time, (utc - utc.iloc[0]).dt.total_seconds().to_numpy())
    assert month_first.clock_origin_s == in_iso.clock_origin_s


@pytest.mark.parametrize(("utc_start", "hours"), [("2026-10-25 00:00:00", -1), ("2026-03-29 00:00:00", 1)])
def test_a_sample_missed_at_the_change_is_a_missed_sample(tmp_path, utc_start, hours):
    """The change read through, the sample missed with it is a gap of two periods, which --resample fills."""
    wall, offset, change = stamped_logs(tmp_path, "Europe/Berlin", utc_start)
    for path in (wall, offset):
        pd.read_csv(path).drop(index=change - 1).to_csv(path, index=False)
    [local], [placed] = (load_runs(p, time="Timestamp", resample=60.0) for p in (wall, offset))
    assert np.array_equal(local.time, placed.time) and np.allclose(local.error, placed.error)
    assert any("summer time" in n for n in local.notes)


def test_a_jittering_clock_is_read_through_its_change():
    utc = pd.Timestamp("2026-10-25 00:50", tz="UTC") + pd.to_timedelta(np.arange(1200.0), unit="s")
    jitter = pd.to_timedelta(np.where(np.arange(len(utc)) % 2, 0.025, -0.025), unit="s")  # steps 50 ms off
    stamps = utc + jitter
    wall = stamps.tz_convert("Europe/Berlin").tz_localize(None)
    frame = pd.DataFrame({"time": wall.strftime("%Y-%m-%d %H:%M:%S.%f"), "T1": 20.0 + 0.001 * np.arange(1200)})
    frame["error_um"] = 2.0 * (frame["T1"] - 20.0)
    [run] = load_runs(frame, time="time", period_tolerance=0.1)
    truth = (stamps - stamps[0]).total_seconds().to_numpy()
    assert np.allclose(run.time, truth, atol=1e-6)


@pytest.mark.parametrize("pause", [("2026-03-29 02:00:00", "Europe/Berlin"), ("2026-03-29 01:29:00", "Europe/London")])
def test_a_pause_from_a_time_the_zone_skips_is_no_change_of_its_clock(pause):
    """02:00 does not exist in Berlin on 29 March (nor 01:29 in London): a pause of an hour from there is a gap."""
    start, zone = pause
    before = pd.Timestamp(start) - pd.to_timedelta(np.arange(60, 0, -1) * 60.0, unit="s")
    after = pd.Timestamp(start) + pd.Timedelta(hours=1, minutes=1) + pd.to_timedelta(np.arange(60) * 60.0, unit="s")
    wall = np.concatenate([before.to_numpy(), [np.datetime64(pd.Timestamp(start))], after.to_numpy()])
    seconds = (pd.DatetimeIndex(wall) - pd.Timestamp("1970-01-01")).total_seconds().to_numpy()
    assert summer_time_changes(seconds) == []
