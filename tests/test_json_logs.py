"""JSON logs read as tables (JSON lines, an array of records, an object of columns, nested values), records of
several kinds merged by ``--resample``, and the ragged ends such records leave. The truth is the same run
written as a plain CSV table, and period means taken by hand."""

from __future__ import annotations

import gzip
import json

import numpy as np
import pandas as pd
import pytest
from support import same_run

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.record_kinds import record_kinds_cycle

TEMPS = ["T1", "T2", "T3", "T4"]


def records(frame: pd.DataFrame) -> list[dict]:
    return json.loads(frame.to_json(orient="records"))


@pytest.mark.parametrize("form", ["lines", "array", "columns", "held", "gzip"])
def test_a_json_log_reads_as_the_plain_table(tmp_path, synthetic, form):
    frame, plain = synthetic
    if form in ("lines", "gzip"):
        text = "\n".join(json.dumps(record) for record in records(frame)) + "\n"
        path = tmp_path / "log.jsonl"
        path.write_text(text)
        if form == "gzip":
            path = tmp_path / "log.jsonl.gz"
            path.write_bytes(gzip.compress(text.encode()))
    else:
        if form == "array":
            document = records(frame)
        elif form == "columns":
            document = json.loads(json.dumps(frame.to_dict(orient="list")))
        else:
            document = {"machine": "lathe 3", "started": "2026-03-02", "samples": records(frame)}
        path = tmp_path / "log.json"
        path.write_text(json.dumps(document, indent=1))
    same_run(load_run(path, temps=TEMPS), plain)


def test_nested_values_are_columns_named_by_their_path_and_a_list_by_the_names_its_objects_give(tmp_path, synthetic):
    frame = synthetic[0]
    nested = [
        {
            "time_s": row.time_s,
            "spindle": {"T": row.T1, "rpm_set": 1000},
            "sensors": [{"id": "bed", "temp": row.T2}, {"id": "column", "temp": row.T3}],
            "air": [row.T4, 20.0],
            "probe": {"z_um": row.error_um},
        }
        for row in frame.itertuples()
    ]
    path = tmp_path / "nested.jsonl"
    path.write_text("\n".join(json.dumps(record) for record in nested))
    temps = ["spindle.T", "sensors.bed.temp", "sensors.column.temp", "air.0"]
    run = load_run(path, temps=temps, error="probe.z_um")
    np.testing.assert_array_equal(run.temps, frame[TEMPS].to_numpy())
    np.testing.assert_array_equal(run.error, frame["error_um"].to_numpy())


@pytest.mark.parametrize("resample", [20.0, None])
def test_records_of_two_kinds_merge_into_period_means(tmp_path, resample):
    """A temperature record every 20 s amid probe readings every 2 s (a printer's probe log): each period of
    20 s averages its probe readings and takes its temperature record, with ``--resample 20`` or unasked (the
    slowest kind's period)."""
    rng = np.random.default_rng(3)
    n_periods, period = 150, 20.0
    temps = 25.0 + np.cumsum(rng.normal(0, 0.05, (n_periods, 2)), axis=0)
    lines = []
    probe_means = []
    for k in range(n_periods):
        start = 1771948547.0 + k * period
        z = 10.0 + 0.02 * k + rng.normal(0, 0.5, 10)
        probe_means.append(z.mean())
        lines += [{"ts": start + 1.0 + 2.0 * j, "z": value} for j, value in enumerate(z[:5])]
        lines.append({"ts": start + 10.0, "btemp": temps[k, 0], "atherms": [{"id": "C", "temp": temps[k, 1]}]})
        lines += [{"ts": start + 11.0 + 2.0 * j, "z": value} for j, value in enumerate(z[5:])]
    lines.append({"ts": 1771948547.0 + n_periods * period + 1.0, "z": 99.0})  # a probe reading after the last record
    path = tmp_path / "probe_log.jsonl"
    path.write_text("\n".join(json.dumps(line) for line in lines))
    run = load_run(path, temps=["btemp", "atherms.C.temp"], error="z", resample=resample)
    np.testing.assert_allclose(run.temps, temps, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.error, probe_means, rtol=0, atol=1e-12)
    assert run.period == pytest.approx(period, rel=1e-9)
    assert any("1 period(s) at the ends without a reading of every column dropped" in note for note in run.notes)
    kinds = "the rows are records of 2 kinds (z every 2 s; btemp, atherms.C.temp every 20 s)"
    assert any(kinds in note for note in run.notes) == (resample is None)


def kinds_table(n: int = 60, stray: int = 0, shared: bool = False) -> pd.DataFrame:
    """A temperature record every 10 s amid two probe records (3 s and 6 s later); ``stray`` rows of a third
    kind; the probe records carrying the temperature too when ``shared``."""
    rows = []
    for k in range(n):
        rows.append({"time_s": 10.0 * k, "T1": 20.0 + 0.01 * k})
        for lag in (3.0, 6.0):
            rows.append({"time_s": 10.0 * k + lag, "z": 0.1 * k, **({"T1": 20.0} if shared else {})})
    rows += [{"time_s": 10.0 * n + k, "spindle": 1.0} for k in range(stray)]
    return pd.DataFrame(rows)


def test_records_of_several_kinds_are_told_from_a_log_with_stray_rows_or_shared_values():
    frame = kinds_table()
    what, period = record_kinds_cycle(frame, "time_s", frame["time_s"].to_numpy())
    assert period == 10.0 and "records of 2 kinds (z every 3 s; T1 every 10 s)" in what
    alone = frame.dropna(subset=["T1"])  # one kind: a plain log
    assert record_kinds_cycle(alone, "time_s", alone["time_s"].to_numpy()) is None
    stray = kinds_table(stray=10)  # 10 of 190 rows of a third kind: covered 95 %, a kind of its own
    assert record_kinds_cycle(stray, "time_s", stray["time_s"].to_numpy())[1] == 10.0
    mixed = kinds_table(stray=3)  # 3 rows: too few to count, and the others still cover 98 %
    assert record_kinds_cycle(mixed, "time_s", mixed["time_s"].to_numpy())[1] == 10.0
    shared = kinds_table(shared=True)  # every row holds T1: kinds that share a value are no record kinds
    assert record_kinds_cycle(shared, "time_s", shared["time_s"].to_numpy()) is None


def test_a_longer_silence_at_an_end_is_named_not_dropped(tmp_path, synthetic):
    frame = synthetic[0]
    sparse = frame.copy()
    sparse.loc[sparse.index[-5:], "T2"] = np.nan  # T2 stops five periods before the end
    path = tmp_path / "stopped.csv"
    sparse.to_csv(path, index=False)
    with pytest.raises(InputError, match=r"row 296, column 'T2' is empty"):
        load_run(path, temps=TEMPS, resample=100.0)
    sparse.loc[sparse.index[-5:-2], "T2"] = frame["T2"].iloc[-5:-2]  # two periods: dropped
    sparse.to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, resample=100.0)
    assert run.n_samples == len(frame) - 2
    np.testing.assert_array_equal(run.temps, frame[TEMPS].to_numpy()[:-2])


@pytest.mark.parametrize(
    "text, message",
    [
        ('{"time_s": 0, "T1": 20.0}\n{"time_s": 100, "T1": 20.1\n', "line 2: not a JSON record"),
        ('{"time_s": 0, "T1": 20.0}\n[1, 2]\n', "line 2: a JSON list, not a record"),
        ('{"machine": "lathe 3", "note": "no samples"}', "JSON without records"),
        ("[1, 2, 3]", "JSON without records"),
        ('{"time_s": [0, 100], "T1": [20.0', "line 1: not JSON"),
    ],
)
def test_a_json_log_that_is_not_one_is_refused_in_one_line_with_nothing_written(tmp_path, capsys, text, message):
    path = tmp_path / "log.json"
    path.write_text(text)
    assert main(["fit", "--data", str(path), "--out", str(tmp_path / "out")]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "log.json: " in line and message in line
    assert not (tmp_path / "out").exists()
