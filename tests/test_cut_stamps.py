"""Time stamps cut to whole minutes or seconds (a spreadsheet saving without seconds, a fast logger's coarse
clock): the rows are spread evenly within their stamps, as the uniform clock that wrote them."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from groupfit.data import load_run
from groupfit.errors import InputError

TEMPS = ["T1", "T2", "T3", "T4"]


def cut_log(frame: pd.DataFrame, period_s: float, start: str, form: str) -> pd.DataFrame:
    """The run at ``period_s`` from ``start``, its stamps written in ``form`` (which drops what is finer)."""
    stamps = pd.Timestamp(start) + pd.to_timedelta(np.arange(len(frame)) * period_s, unit="s")
    return frame.drop(columns="time_s").assign(Time=stamps.strftime(form))[["Time", *frame.columns[1:]]]


@pytest.mark.parametrize(
    "period_s, start, form",
    [
        (15.0, "2026-03-02 08:00:07", "%Y/%m/%d %H:%M"),  # Excel's date format without seconds
        (20.0, "2026-03-02 23:50:41", "%d.%m.%Y %H:%M"),  # across midnight
        (7.0, "2026-03-02 08:00:00", "%Y-%m-%d %H:%M"),  # a period that does not divide the minute
        (0.25, "2026-03-02 08:00:00.5", "%Y-%m-%d %H:%M:%S"),  # a fast logger stamping whole seconds
        (100.0, "2026-03-02 08:00:30", "%Y-%m-%d %H:%M"),  # no stamp repeats: steps of 60 and 120 s
        (7.5, "2026-03-02 08:00:00.2", "%H:%M:%S"),  # seconds: 1 or 2 rows a stamp, no row alone in most
    ],
)
def test_rows_under_cut_stamps_are_spread_as_the_uniform_clock_that_wrote_them(
    tmp_path, synthetic, period_s, start, form
):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    cut_log(frame, period_s, start, form).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, time_is_default=True)
    np.testing.assert_allclose(run.time, np.arange(len(frame)) * period_s, atol=1e-6)
    assert run.period == pytest.approx(period_s, rel=1e-9)
    np.testing.assert_array_equal(run.temps, plain.temps)
    assert any("the rows are spread evenly" in note for note in run.notes)


def test_stamps_no_uniform_clock_fits_are_still_refused(tmp_path, synthetic):
    frame, _ = synthetic
    path = tmp_path / "log.csv"
    log = cut_log(frame, 15.0, "2026-03-02 08:00:00", "%Y-%m-%d %H:%M")
    log.drop(index=range(100, 140)).to_csv(path, index=False)  # ten minutes missing: no one clock fits
    with pytest.raises(InputError, match=r"column 'Time' is not strictly increasing"):
        load_run(path, temps=TEMPS, time_is_default=True)
    minutes = cut_log(frame, 60.0, "2026-03-02 08:00:20", "%Y-%m-%d %H:%M").drop(index=50)  # one sample missed
    minutes.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"sampling is not uniform: rows 50 to 51 of column 'Time'"):
        load_run(path, temps=TEMPS, time_is_default=True)
    seconds = frame.copy()
    seconds.loc[10, "time_s"] = seconds.loc[9, "time_s"]  # one duplicated stamp in a log of distinct ones
    seconds.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"column 'time_s' is not strictly increasing at row 11"):
        load_run(path, temps=TEMPS)
