"""Tables read as the user wrote them: any of three delimiters, date-time time columns, Parquet headers;
and the compare verb's projection of its GA fits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC

from groupfit import fit_budget
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.fit_budget import check_projection, projecting
from groupfit.textlayout import decode, layout_of

TEMPS = ["T1", "T2", "T3", "T4"]


@pytest.fixture(scope="module")
def comma():
    return load_run(SYNTHETIC, temps=TEMPS)


@pytest.mark.parametrize("sep, suffix", [(";", ".csv"), ("\t", ".tsv"), ("\t", ".txt"), (",", ".csv")])
def test_a_semicolon_or_tab_table_reads_as_the_comma_one(tmp_path, comma, sep, suffix):
    path = tmp_path / f"run{suffix}"
    pd.read_csv(SYNTHETIC).to_csv(path, sep=sep, index=False)
    assert layout_of(decode(path.read_bytes())).sep == sep
    run = load_run(path, temps=TEMPS)
    np.testing.assert_array_equal(run.temps, comma.temps)
    np.testing.assert_array_equal(run.error, comma.error)
    assert run.period == comma.period


def test_a_decimal_comma_does_not_take_the_comma_as_delimiter(tmp_path):
    # a European export: the header decides (semicolons), though the numbers below carry decimal commas
    (tmp_path / "eu.csv").write_text("time_s;T1;error_um\n0;20,5;1,0\n")
    assert layout_of(decode((tmp_path / "eu.csv").read_bytes())).sep == ";"


@pytest.mark.parametrize("unit", ["datetime", "timedelta"])
def test_a_date_time_column_is_read_as_seconds(tmp_path, comma, unit):
    frame = pd.read_csv(SYNTHETIC)
    offset = pd.to_timedelta(frame["time_s"], unit="s")
    frame["time_s"] = pd.Timestamp("2024-03-01 06:00", tz="UTC") + offset if unit == "datetime" else offset
    frame.to_parquet(tmp_path / "run.parquet")
    run = load_run(tmp_path / "run.parquet", temps=TEMPS)
    # a date-time counts from the first row; a duration is its own seconds
    expected = comma.time - comma.time[0] if unit == "datetime" else comma.time
    np.testing.assert_allclose(run.time, expected, rtol=0, atol=1e-9)
    assert run.period == pytest.approx(comma.period)


def test_a_missing_date_time_is_named_with_its_row(tmp_path):
    frame = pd.read_csv(SYNTHETIC)
    frame["time_s"] = pd.Timestamp("2024-03-01") + pd.to_timedelta(frame["time_s"], unit="s")
    frame.loc[7, "time_s"] = pd.NaT
    frame.to_parquet(tmp_path / "run.parquet")
    with pytest.raises(InputError, match="row 8, column 'time_s' is empty"):
        load_run(tmp_path / "run.parquet", temps=TEMPS)


def test_the_projection_of_the_ga_fits(monkeypatch):
    lines = []
    # 2 s for p = 1, 23 feasible breaks: 2 · 23 · 24 / 2 = 552 s, under 900 s: said, not refused
    check_projection(2.0, pmax=23, asked=50, budget_s=900.0, estimate=lines.append)
    assert lines == ["grouped models p = 1…23 (the largest feasible p; --pmax 50 asked) by the GA: about 9 min"]
    with pytest.raises(InputError, match="about 18 min, over the budget of 15 min: lower --pmax"):
        check_projection(4.0, pmax=23, asked=23, budget_s=900.0, estimate=lines.append)
    check_projection(4.0, pmax=23, asked=23, budget_s=None, estimate=lines.append)  # --no-budget: said, run
    check_projection(0.1, pmax=4, asked=4, budget_s=900.0, estimate=lines.append)  # 1 s: nothing said
    assert len(lines) == 2
    # through compare's progress: timed from the first GA fit's end to the second's (fit 2 takes twice fit 1)
    seen = []
    call = projecting(lambda *a: seen.append(a), asked=23, budget_s=1e-9, estimate=lines.append)
    call("exact path", 1.0)
    call("grouped", 1 / 23)
    with pytest.raises(InputError, match="p = 1…23 by the GA"):
        call("grouped", 2 / 23)
    call("grouped", 3 / 23)  # projected once only
    assert seen == [("exact path", 1.0), ("grouped", 1 / 23), ("grouped", 2 / 23), ("grouped", 3 / 23)]
    # with the stage's start (its call at 0) the first fit alone refuses a run over the budget
    call = projecting(lambda *a: None, asked=23, budget_s=1e-9, estimate=lines.append)
    call("grouped", 0.0)
    with pytest.raises(InputError, match="p = 1…23 by the GA"):
        call("grouped", 1 / 23)
    # within the budget: checked after the first fit, said once, after the second (timed alone)
    clock = iter([0.0, 100.0, 400.0])  # fit 1 takes 100 s, fit 2 300 s: 150 s a fit, 4 fits 10 × 150 s
    monkeypatch.setattr(fit_budget.time, "perf_counter", lambda: next(clock))
    call = projecting(lambda *a: None, asked=4, budget_s=1e9, estimate=lines.append)
    said = len(lines)
    call("grouped", 0.0)
    call("grouped", 1 / 4)
    assert len(lines) == said
    call("grouped", 2 / 4)
    call("grouped", 3 / 4)
    assert lines[said:] == ["grouped models p = 1…4 by the GA: about 25 min"]
    clock = iter([0.0, 200.0, 300.0])  # the second fit faster than twice the first: the first's projection said
    call = projecting(lambda *a: None, asked=4, budget_s=1e9, estimate=lines.append)
    for fraction in (0.0, 1 / 4, 2 / 4):
        call("grouped", fraction)
    assert lines[-1] == "grouped models p = 1…4 by the GA: about 33 min"
