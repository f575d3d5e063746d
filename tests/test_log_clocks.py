"""Clocks of real logs: units named in other words, elapsed hours past a day, a restart under --resample."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from test_messy_rows import fitted_coefficients

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.timestamps import TIME_NAME, text_seconds

TEMPS = ["T1", "T2", "T3", "T4"]


@pytest.mark.parametrize(
    "name, per_second",
    [("Zeit [Min.]", 1 / 60), ("Zeit [Std]", 1 / 3600), ("Time (hrs.)", 1 / 3600), ("Zeit [Sek]", 1.0)],
)
def test_a_unit_of_time_in_other_words_is_read(tmp_path, synthetic, name, per_second):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.assign(time_s=frame["time_s"] * per_second).rename(columns={"time_s": name}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS)
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)
    assert run.period == pytest.approx(plain.period, rel=1e-9)


@pytest.mark.parametrize(
    "name, per_second, asked",
    [("Time", 1 / 60, True), ("elapsed", 1 / 3600, True), ("Time [min]", 1 / 60, False), ("Time", 1.0, False)],
)
def test_a_run_of_minutes_on_a_time_column_naming_no_unit_gets_a_note_asking_for_its_unit(
    tmp_path, synthetic, name, per_second, asked
):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.assign(time_s=frame["time_s"] * per_second).rename(columns={"time_s": name}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS)
    span = float(plain.time[-1] - plain.time[0])
    assert span > 1800.0  # the run as it was logged lasts hours
    note = f"the run lasts {span * per_second:g} s by column '{name}', read in seconds as its name gives no unit"
    assert any(note in line for line in run.notes) == asked


def test_a_bracketed_word_that_is_no_unit_of_time_is_refused_and_a_time_zone_is_not_one(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.rename(columns={"time_s": "Zeit [Takte]"}).to_csv(path, index=False)
    with pytest.raises(InputError, match=r"column 'Zeit \[Takte\]': 'Takte' is not a unit of time"):
        load_run(path, temps=TEMPS)
    frame.rename(columns={"time_s": "Time (UTC)"}).to_csv(path, index=False)
    np.testing.assert_array_equal(load_run(path, temps=TEMPS).time, plain.time)


@pytest.mark.parametrize("form", ["elapsed", "comma", "colon"])
def test_elapsed_hours_past_a_day_and_fractions_after_a_comma_or_colon_are_read(tmp_path, synthetic, form):
    frame, plain = synthetic
    seconds = frame["time_s"].to_numpy(dtype=float) * 3.7  # the synthetic run stretched past 24 h
    assert seconds[-1] > 86400.0
    if form == "elapsed":  # a spreadsheet's [h]:mm:ss
        text = [f"{int(s // 3600)}:{int(s % 3600 // 60):02d}:{s % 60:06.3f}" for s in seconds]
    else:  # a time of day with milliseconds after a comma (German) or a colon (a data logger)
        seconds = frame["time_s"].to_numpy(dtype=float) / 10.0 + 0.25
        mark = "," if form == "comma" else ":"
        text = [f"08:{int(s // 60):02d}:{int(s % 60):02d}{mark}{round(s % 1 * 1000):03d}" for s in seconds]
    path = tmp_path / "log.csv"
    frame.assign(time_s=text).rename(columns={"time_s": "Elapsed Time"}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time="Elapsed Time")
    np.testing.assert_allclose(run.time, seconds - seconds[0], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(run.temps, plain.temps)


@pytest.mark.parametrize("form", ["pandas", "python", "short"])
def test_a_duration_led_by_days_is_read_as_pandas_reads_it(tmp_path, synthetic, form):
    frame, plain = synthetic
    durations = pd.to_timedelta(frame["time_s"].to_numpy(dtype=float) * 3.7, unit="s")  # past 24 h
    if form == "pandas":  # 1 days 02:13:20
        text = durations.astype(str)
    elif form == "python":  # 1 day, 2:13:20
        text = [str(duration.to_pytimedelta()) for duration in durations]
    else:  # 1d 02:13:20
        text = [f"{d.days}d {d.seconds // 3600:02d}:{d.seconds // 60 % 60:02d}:{d.seconds % 60:02d}" for d in durations]
    assert any("day" in str(cell) or "d " in str(cell) for cell in text)
    path = tmp_path / "log.csv"
    frame.assign(time_s=text).rename(columns={"time_s": "Elapsed"}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time="Elapsed")
    seconds = pd.to_timedelta(pd.Series(durations)).dt.total_seconds().to_numpy()
    np.testing.assert_allclose(run.time, seconds - seconds[0], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(run.temps, plain.temps)


@pytest.mark.parametrize("name", ["Timestamp", "Time"])
def test_serial_days_under_a_time_name_are_read_in_days_when_only_days_make_a_run_of_them(tmp_path, synthetic, name):
    frame, plain = synthetic
    days = 46082.25 + frame["time_s"].to_numpy(dtype=float) / 86400.0  # a spreadsheet's date-times as numbers
    path = tmp_path / "log.csv"
    frame.assign(time_s=days).rename(columns={"time_s": name}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time=name)
    np.testing.assert_allclose(run.time - run.time[0], plain.time - plain.time[0], rtol=0, atol=1e-4)
    assert any("holds spreadsheet serial dates" in note for note in run.notes)
    assert not any("the run lasts" in note for note in run.notes)
    seconds = 40000.0 + frame["time_s"].to_numpy(dtype=float) / 10.0  # seconds since midnight, a run of hours
    assert seconds[-1] - seconds[0] > 1800.0
    frame.assign(time_s=seconds).rename(columns={"time_s": name}).to_csv(path, index=False)
    in_seconds = load_run(path, temps=TEMPS, time=name)
    np.testing.assert_allclose(in_seconds.time - in_seconds.time[0], seconds - seconds[0], rtol=1e-9)


def test_resample_refuses_two_recordings_in_one_file_instead_of_averaging_them(tmp_path, synthetic, capsys):
    frame = synthetic[0]
    restarted = frame.copy()
    restarted.loc[150:, "time_s"] -= restarted.loc[150, "time_s"]  # the logger powered up again at row 151
    path = tmp_path / "two.csv"
    restarted.to_csv(path, index=False)
    argv = ["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--resample", "100", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "starts again at row 151" in err[0] and "split the file before row 151" in err[0]
    assert "sort the rows" not in err[0] and not (tmp_path / "o").exists()


def test_a_modelling_file_not_read_as_one_run_is_not_continued_and_the_note_says_why(tmp_path, synthetic, capsys):
    """A next run whose clock continues a modelling log with a gap (fitted with --resample) is replayed afresh."""
    frame = synthetic[0]
    period = float(frame["time_s"].iloc[1] - frame["time_s"].iloc[0])
    gapped = frame.iloc[:200].copy()
    gapped.loc[120:, "time_s"] += 10 * period  # the logger paused
    rest = frame.iloc[200:].copy()
    rest["time_s"] += 10 * period  # the next run's clock goes on from the modelling file's
    model_run, next_run = tmp_path / "model_run.csv", tmp_path / "next_run.csv"
    gapped.to_csv(model_run, index=False)
    rest.to_csv(next_run, index=False)
    fit = ["fit", "--data", str(model_run), "--temps", ",".join(TEMPS), "--p", "0", "--resample", str(period)]
    assert main([*fit, "--quiet", "--out", str(tmp_path / "m")]) == 0
    model = str(tmp_path / "m" / "model.json")
    capsys.readouterr()
    assert main(["replay", model, "--data", str(next_run), "--json", str(tmp_path / "r.json")]) == 0
    out = capsys.readouterr().out
    assert "which is not read as one run here (sampling is not uniform" in out and "starts afresh" in out
    assert main(["replay", model, "--data", str(next_run), "--fresh", "--json", str(tmp_path / "f.json")]) == 0
    replayed, fresh = (json.loads((tmp_path / f).read_text()) for f in ("r.json", "f.json"))
    assert replayed["rms_um"] == fresh["rms_um"] and replayed["samples"] == fresh["samples"]


@pytest.mark.parametrize("form", ["%Y-%m-%d %H:%M:%S %Z", "%d.%m.%Y %H:%M:%S %Z", "%d-%b-%Y %H:%M:%S %Z"])
def test_stamps_naming_their_time_zone_cross_a_clock_change_evenly(form):
    # Central Europe changes to summer time at 01:00 UTC on 2026-03-29: CET 01:59 is followed by CEST 03:00
    utc = pd.date_range("2026-03-29 00:30", periods=90, freq="60s", tz="UTC")
    column = pd.Series(utc.tz_convert("Europe/Berlin").strftime(form))
    assert column.str.endswith(" CET").any() and column.str.endswith(" CEST").any()
    np.testing.assert_array_equal(text_seconds(column, "time", "run.csv"), 60.0 * np.arange(90))


@pytest.mark.parametrize("form", ["%d-%m-%y %H:%M:%S", "%d-%b-%Y %H:%M:%S", "%d %b %Y %H:%M", "%b %d %Y %I:%M %p"])
def test_dates_with_two_digit_years_or_month_names_are_read(form):
    stamps = pd.date_range("2026-02-27 22:00", periods=200, freq="120s")  # across the end of February
    column = pd.Series(stamps.strftime(form))
    np.testing.assert_array_equal(text_seconds(column, "time", "run.csv"), 120.0 * np.arange(200))


def _split_stamps(frame: pd.DataFrame, period_s: float, *, name: str = "ms", fractions: bool = False) -> pd.DataFrame:
    """The run at ``period_s``, stamped as a Graphtec logger stamps it: the date-time in whole seconds (or with
    its fractions, ``fractions``), then its milliseconds in a column of their own."""
    stamps = pd.Timestamp("2026-03-01 23:59:00") + pd.to_timedelta(np.arange(len(frame)) * period_s, unit="s")
    form = "%Y/%m/%d %H:%M:%S.%f" if fractions else "%Y/%m/%d %H:%M:%S"
    split = pd.DataFrame({"Date&Time": stamps.strftime(form), name: stamps.microsecond // 1000})
    return pd.concat([split, frame.drop(columns="time_s")], axis=1)


@pytest.mark.parametrize("period_s, name", [(0.5, "ms"), (0.25, "msec"), (0.1, "[ms]"), (0.2, "Millisekunden")])
def test_a_stamp_in_whole_seconds_with_its_milliseconds_in_the_next_column_is_read_as_one_time(
    tmp_path, synthetic, period_s, name
):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    _split_stamps(frame, period_s, name=name).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS)
    truth = (plain.time - plain.time[0]) * period_s / plain.period
    np.testing.assert_allclose(run.time, truth, atol=1e-9)  # across midnight, as the stamps start at 23:59
    assert run.period == pytest.approx(period_s, rel=1e-9)
    assert name not in run.frame.columns
    np.testing.assert_array_equal(run.temps, plain.temps)
    assert any(f"with the milliseconds of column '{name}'" in note for note in run.notes)


def test_milliseconds_are_added_only_to_a_stamp_in_whole_seconds_and_only_from_the_column_after_it(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    truth = (plain.time - plain.time[0]) * 0.5 / plain.period
    _split_stamps(frame, 0.5, fractions=True).to_csv(path, index=False)  # the stamp has its own fractions
    np.testing.assert_allclose(load_run(path, temps=TEMPS).time, truth, atol=1e-9)
    elsewhere = _split_stamps(frame, 0.5)
    elsewhere = elsewhere[[c for c in elsewhere.columns if c != "ms"] + ["ms"]]
    elsewhere.to_csv(path, index=False)
    run = load_run(path, temps=TEMPS)  # not the stamps' milliseconds: the rows are spread within their seconds
    np.testing.assert_allclose(run.time, truth, atol=1e-9)
    assert "ms" in run.frame.columns and any("stamps its rows in whole seconds" in note for note in run.notes)
    slow = _split_stamps(frame, plain.period)  # whole seconds: the column of zeros is dropped without a note
    slow.to_csv(path, index=False)
    run = load_run(path)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], atol=1e-9)
    assert "ms" not in run.frame.columns and "ms" not in run.temp_names
    assert not any("with the milliseconds of column" in note for note in run.notes)


def test_a_graphtec_log_at_half_a_second_fits_the_model_of_the_plain_run(tmp_path, synthetic):
    frame, _ = synthetic
    plain = frame.assign(time_s=np.arange(len(frame)) * 0.5)
    plain.to_csv(tmp_path / "plain.csv", index=False)
    split = _split_stamps(frame, 0.5)
    units = pd.DataFrame([["", ""] + ["degC" if c.startswith("T") else "um" for c in split.columns[2:]]])
    units.columns = split.columns
    header = ['"MODEL","GL240"', '"Interval","500ms"', ""]
    body = pd.concat([units, split.astype(object)]).to_csv(index=False)
    (tmp_path / "graphtec.csv").write_text("\n".join(header) + "\n" + body)
    plain_fit, graphtec_fit = fitted_coefficients(tmp_path, tmp_path / "plain.csv", tmp_path / "graphtec.csv")
    np.testing.assert_allclose(graphtec_fit, plain_fit, rtol=1e-9)


@pytest.mark.parametrize(
    "name, per_second",
    [
        ("Relative Time", 1.0),
        ("Run time [s]", 1.0),
        ("Sample time", 1.0),
        ("Laufzeit [min]", 1 / 60),
        ("Messzeit", 1.0),
        ("Zeitpunkt", 1.0),
        ("X_Value", 1.0),
        ("Seconds", 1.0),
        ("Sekunden", 1.0),
        ("Hours", 1 / 3600),
        ("Time of day", 1.0),
        ("Temps (s)", 1.0),
        ("Temps écoulé [min]", 1 / 60),
        ("Horodatage", 1.0),
        ("Tiempo [s]", 1.0),
    ],
)
def test_a_time_column_named_in_other_words_is_found_and_read_in_its_unit(tmp_path, synthetic, name, per_second):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.assign(time_s=frame["time_s"] * per_second).rename(columns={"time_s": name}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time_is_default=True)
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)
    assert any(f"time from column '{name}'" in note for note in run.notes)


@pytest.mark.parametrize("name", ["temps_C", "Temps [°C]", "temps_degC"])
def test_temperatures_named_temps_are_not_taken_for_the_time(name):
    assert TIME_NAME.match(name) is None


def test_a_log_without_a_time_or_an_error_column_named_as_one_says_which_option_names_it(tmp_path, synthetic):
    frame, _ = synthetic
    path = tmp_path / "log.csv"
    frame.rename(columns={"time_s": "Uhr"}).to_csv(path, index=False)
    with pytest.raises(InputError, match=r"column 'time_s' not found \(name the time column with --time COLUMN\)"):
        load_run(path, temps=TEMPS, time_is_default=True)
    frame.rename(columns={"error_um": "Z-Achse"}).to_csv(path, index=False)
    with pytest.raises(
        InputError, match=r"'error_um' not found \(name the thermal error's column with --error COLUMN\)"
    ):
        load_run(path, temps=TEMPS, error_is_default=True)
