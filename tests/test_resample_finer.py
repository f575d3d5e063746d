"""``--resample`` to a period shorter than the log's: missed readings counted in the log's own cycles.

Resampling a 60 s log to 20 s (to replay it on a model fitted at 20 s) leaves two empty periods between every
two readings. Those are not missed readings: the log is interpolated between its rows (checked against
``numpy.interp``), one missed row of the log is one missed cycle, and a sensor silent for longer than the
interpolation covers stays empty instead of being bridged by the empty periods around each row.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.resample import GAP_PERIODS, resample_frame

LOG_PERIOD = 60.0
PERIOD = 20.0


def _log(n: int = 120) -> pd.DataFrame:
    t = np.arange(n) * LOG_PERIOD
    rng = np.random.default_rng(7)
    t1 = 20.0 + np.cumsum(rng.normal(0.0, 0.05, n))
    t2 = 21.0 + np.cumsum(rng.normal(0.0, 0.05, n))
    return pd.DataFrame({"time_s": t, "T1": t1, "T2": t2, "error_um": 3.0 * (t1 - 20.0) - 2.0 * (t2 - 21.0)})


def _resample(frame: pd.DataFrame):
    return resample_frame(frame, time="time_s", period_s=PERIOD, label="log.csv", measured=("error_um",))


def _interp(frame: pd.DataFrame, column: str, at: np.ndarray) -> np.ndarray:
    known = frame[column].notna().to_numpy()
    return np.interp(at, frame["time_s"].to_numpy()[known], frame[column].to_numpy()[known])


def test_a_whole_log_is_interpolated_between_its_rows():
    log = _log()
    out = _resample(log)
    assert len(out.pieces) == 1 and out.gaps == [] and out.missed == 0
    piece = out.pieces[0]
    assert len(piece) == 3 * (len(log) - 1) + 1
    for column in ("T1", "T2", "error_um"):
        np.testing.assert_allclose(piece[column], _interp(log, column, piece["time_s"].to_numpy()), atol=1e-12)


def test_one_missed_row_of_the_log_is_a_missed_cycle_not_a_gap():
    log = _log().drop(index=[40]).reset_index(drop=True)
    out = _resample(log)
    assert len(out.pieces) == 1 and out.gaps == []
    piece = out.pieces[0]
    np.testing.assert_allclose(piece["T1"], _interp(log, "T1", piece["time_s"].to_numpy()), atol=1e-12)


@pytest.mark.parametrize("missed", [GAP_PERIODS, GAP_PERIODS + 1])
def test_the_log_is_split_after_more_than_the_missed_cycles_interpolation_covers(missed):
    log = _log()
    before, after = float(log["time_s"][39]), float(log["time_s"][40 + missed])
    out = _resample(log.drop(index=range(40, 40 + missed)).reset_index(drop=True))
    if missed <= GAP_PERIODS:
        assert len(out.pieces) == 1 and out.gaps == []
    else:
        assert len(out.pieces) == 2 and out.gaps == [(before, after)]


def test_a_sensor_silent_longer_than_the_interpolation_covers_stays_empty():
    log = _log()
    log.loc[50 : 50 + GAP_PERIODS, "T2"] = np.nan  # one reading more than is filled
    piece = _resample(log).pieces[0]
    t = piece["time_s"].to_numpy()
    silent = (t > log["time_s"][49]) & (t < log["time_s"][51 + GAP_PERIODS])
    assert np.isnan(piece["T2"].to_numpy()[silent]).all()
    assert np.isfinite(piece["T2"].to_numpy()[~silent]).all()
    assert np.isfinite(piece["T1"]).all()


def test_a_sensor_missing_a_few_readings_is_interpolated_with_the_periods_around_them():
    log = _log()
    log.loc[50 : 49 + GAP_PERIODS, "T2"] = np.nan
    out = _resample(log)
    piece = out.pieces[0]
    assert out.missed == GAP_PERIODS
    np.testing.assert_allclose(piece["T2"], _interp(log, "T2", piece["time_s"].to_numpy()), atol=1e-12)


def test_a_sparse_measured_error_is_never_made_up():
    log = _log()
    log.loc[log.index % 5 != 0, "error_um"] = np.nan  # a probe reading every fifth row
    piece = _resample(log).pieces[0]
    read = np.isin(piece["time_s"].to_numpy(), log["time_s"][log.index % 5 == 0].to_numpy() + 0.0)
    assert np.isfinite(piece["error_um"].to_numpy()[read]).all()
    assert np.isnan(piece["error_um"].to_numpy()[~read]).all()


def test_fit_refuses_a_sensor_silence_that_finer_resampling_would_have_bridged(tmp_path, capsys):
    log = _log(180)
    log.loc[50:59, "T2"] = np.nan
    path = tmp_path / "silent.csv"
    log.to_csv(path, index=False)
    assert main(["fit", "--data", str(path), "--p", "0", "--resample", "20", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "column 'T2'" in err and "more than --resample SECONDS interpolates" in err
    assert not (tmp_path / "out").exists()


def test_a_refused_silence_counts_the_readings_the_log_missed_not_the_periods(tmp_path, capsys):
    log = _log(180)
    log.loc[50:58, "T2"] = np.nan  # ten minutes without a reading of T2
    path = tmp_path / "silent.csv"
    log.to_csv(path, index=False)
    t = log["time_s"].to_numpy()
    read = t[log["T2"].notna().to_numpy()]
    silent = (t > read[read < 3000.0][-1]) & (t < read[read > 3000.0][0])
    missed = int(silent.sum())  # the log's rows in the silence
    periods = int(round((read[read > 3000.0][0] - read[read < 3000.0][-1]) / PERIOD)) - 1
    assert (missed, periods) == (9, 29)
    assert main(["fit", "--data", str(path), "--p", "0", "--resample", "20", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"({missed} missed reading(s) of the log in that column, {periods} period(s) without a value)" in err
    assert f"miss {missed} readings of the log in a row ({periods} periods)" in err
    assert f"miss {periods} readings" not in err
    silent_rows = np.flatnonzero(silent) + 1  # the log's rows in the silence, as a user counts them
    assert f"(the log's rows {silent_rows[0]}-{silent_rows[-1]}) miss {missed} readings" in err
    first_empty = int(err.split(": row ")[1].split(" ")[0]) - 1  # the resampled row the refusal names first
    start = t[0] + first_empty * PERIOD - PERIOD / 2  # that period's left edge: the bins are centred on the rows
    after = int(np.searchsorted(t, start))  # the log's first row at or after it (0-based)
    assert t[after] >= start + PERIOD  # no row of the log in that period: it falls between two of them
    assert f"row {first_empty + 1} of the resampled run (between the log's rows {after} and {after + 1})" in err
