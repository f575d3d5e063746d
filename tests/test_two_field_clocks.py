"""Elapsed times of two fields (``m:ss``, ``h:mm``): read by the form the column's name gives, refused when
nothing says which, and a time of day ``hh:mm`` still read as one."""

from __future__ import annotations

import numpy as np
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError

TEMPS = ["T1", "T2", "T3", "T4"]


def minutes_seconds(seconds, decimals: int = 0) -> list[str]:
    width = 3 + decimals if decimals else 2
    return [f"{int(s // 60)}:{s % 60:0{width}.{decimals}f}" for s in seconds]


def hours_minutes(seconds) -> list[str]:
    return [f"{int(s // 3600)}:{int(round(s % 3600 / 60)):02d}" for s in seconds]


def written(tmp_path, frame, name, text):
    path = tmp_path / "log.csv"
    frame.assign(time_s=text).rename(columns={"time_s": name}).to_csv(path, index=False)
    return path


@pytest.mark.parametrize("name", ["Zeit [min]", "time [mm:ss]", "Dauer (min:sek)", "elapsed_min"])
def test_minutes_and_seconds_are_read_on_the_form_the_name_gives(tmp_path, synthetic, name):
    frame, plain = synthetic
    seconds = frame["time_s"].to_numpy(dtype=float)
    assert seconds[-1] / 60 > 23  # the minutes pass any hour of a day
    run = load_run(written(tmp_path, frame, name, minutes_seconds(seconds)), temps=TEMPS, time=name)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], rtol=0, atol=1e-9)
    assert run.period == pytest.approx(plain.period, rel=1e-12)
    np.testing.assert_array_equal(run.temps, plain.temps)


def test_a_short_run_of_minutes_and_seconds_is_not_read_as_hours_and_minutes(tmp_path, synthetic):
    """Every minute within 0…23 would read as a time of day, 60 times too slow, were the name not read."""
    frame, plain = synthetic
    seconds = frame["time_s"].to_numpy(dtype=float) / 25.0  # 4 s apart, 20 min in all
    assert seconds[-1] / 60 < 23
    run = load_run(written(tmp_path, frame, "time [mm:ss]", minutes_seconds(seconds)), temps=TEMPS, time="time [mm:ss]")
    np.testing.assert_allclose(run.time, seconds - seconds[0], rtol=0, atol=1e-9)


def test_seconds_with_a_fraction_make_the_fields_minutes_and_seconds_whatever_the_name(tmp_path, synthetic):
    frame, plain = synthetic
    seconds = frame["time_s"].to_numpy(dtype=float) / 8.0  # 12.5 s apart
    run = load_run(written(tmp_path, frame, "Time", minutes_seconds(seconds, 1)), temps=TEMPS, time="Time")
    np.testing.assert_allclose(run.time, seconds - seconds[0], rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", ["elapsed (h)", "Dauer [hh:mm]", "Laufzeit (Std:Min)"])
def test_hours_and_minutes_past_a_day_are_read_on_the_form_the_name_gives(tmp_path, synthetic, name):
    frame, plain = synthetic
    seconds = frame["time_s"].to_numpy(dtype=float) * 6.0  # 10 min apart, 50 h in all
    assert seconds[-1] > 86400.0
    run = load_run(written(tmp_path, frame, name, hours_minutes(seconds)), temps=TEMPS, time=name)
    np.testing.assert_allclose(run.time, seconds - seconds[0], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(run.temps, plain.temps)


def test_two_fields_past_23_are_refused_when_nothing_says_which_with_the_row_and_both_forms(
    tmp_path, synthetic, capsys
):
    frame, _ = synthetic
    seconds = frame["time_s"].to_numpy(dtype=float)
    path = written(tmp_path, frame, "Time", minutes_seconds(seconds))
    with pytest.raises(InputError) as refused:
        load_run(path, temps=TEMPS, time="Time")
    row = int(np.flatnonzero(seconds // 60 > 23)[0])
    value = minutes_seconds(seconds)[row]
    message = str(refused.value)
    assert f"row {row + 1}, column 'Time': '{value}'" in message
    assert "'Time [mm:ss]' or 'Time [hh:mm]'" in message
    out = tmp_path / "out"
    argv = ["fit", "--data", str(path), "--time", "Time", "--temps", ",".join(TEMPS), "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"'{value}' is an elapsed time of two fields" in err[0]
    assert not out.exists()


def test_a_time_of_day_named_hh_mm_passes_midnight_as_a_time_of_day(tmp_path, synthetic):
    frame, plain = synthetic
    seconds = 22 * 3600.0 + frame["time_s"].to_numpy(dtype=float) * 0.6  # one a minute from 22:01, past midnight
    clock = [f"{int(s // 3600) % 24:02d}:{int(round(s % 3600 / 60)):02d}" for s in seconds]
    assert "00:00" in clock
    run = load_run(written(tmp_path, frame, "Uhrzeit [hh:mm]", clock), temps=TEMPS, time="Uhrzeit [hh:mm]")
    np.testing.assert_allclose(run.time, seconds - seconds[0], rtol=0, atol=1e-6)
