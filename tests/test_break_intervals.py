"""Break-position confidence intervals: Bai (1997) against strucchange, and the bootstrap.

strucchange's intervals were recorded by ``tests/data/strucchange/record.R``
(strucchange 1.5-3) on its documented examples, so these tests need no R.
"""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.grouping import Constraints
from groupfit.inference import break_intervals
from groupfit.inference.bootstrap import block_resample, bootstrap_break_intervals, percentile_intervals
from groupfit.inference.break_intervals import argmax_cdf, argmax_quantile, bai_intervals
from groupfit.models import GroupedRegressor
from groupfit.objective import SegmentCost
from groupfit.search.exact import exact_is_cheap, solve_exact

ROOT = Path(__file__).resolve().parents[1]
RECORDED = ROOT / "tests" / "data" / "strucchange"
EXAMPLES = json.loads((RECORDED / "intervals.json").read_text())


def example(name):
    frame = pd.read_csv(RECORDED / f"{name}.csv")
    y = frame.pop("y").to_numpy()
    return frame, y


@pytest.mark.parametrize("name", sorted(EXAMPLES))
@pytest.mark.parametrize("het", [True, False], ids=["het", "hom"])
def test_bai_intervals_match_strucchange(name, het):
    frame, y = example(name)
    X = frame.to_numpy()
    compared = 0
    for m in range(1, 5):
        rows = [r for r in EXAMPLES[name]["intervals"] if r["m"] == m and r["het"] is het]
        assert len(rows) == m
        got = bai_intervals(X, y, [r["break"] for r in rows], level=0.95, het_reg=het, het_err=het)
        for want, interval in zip(rows, got):
            assert interval.brk == want["break"] and interval.method == "bai"
            if want["lower"] is None:
                assert interval.lower is None and interval.upper is None
                continue
            assert abs(interval.lower - want["lower"]) <= 1, (m, want, interval)
            assert abs(interval.upper - want["upper"]) <= 1, (m, want, interval)
            compared += 2
    assert compared > 0


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_exact_solver_finds_strucchanges_breaks(name):
    """sse, n = 0, intercept per the formula, minimum segment size h: the same breaks for m = 1…4."""
    frame, y = example(name)
    X = frame.drop(columns="(Intercept)").to_numpy()
    cost = SegmentCost(X, y, n=0, objective="sse", fit_intercept=True)
    result = solve_exact(cost, Constraints(len(y), 0, EXAMPLES[name]["h"]), 4)
    for m in range(1, 5):
        want = [r["break"] for r in EXAMPLES[name]["intervals"] if r["m"] == m and r["het"]]
        assert result.breaks[m] == want


def test_argmax_distribution_is_a_distribution():
    grid = np.linspace(-200, 200, 81)
    for xi, phi1, phi2 in [(1, 1, 1), (2.5, 1, 0.4), (0.3, 2, 1)]:
        values = np.array([argmax_cdf(x, xi, phi1, phi2) for x in grid])
        assert np.all(np.diff(values) >= -1e-12)
        assert values[0] < 0.01 and values[-1] > 0.99
    # symmetric case: P(argmax V <= 0) = 1/2 and the quantiles mirror each other
    assert argmax_cdf(0.0) == pytest.approx(0.5)
    assert argmax_quantile(0.975) == pytest.approx(-argmax_quantile(0.025), rel=1e-8)
    assert argmax_cdf(argmax_quantile(0.975, 2.0, 1.0, 0.5), 2.0, 1.0, 0.5) == pytest.approx(0.975)


def shifted_series(seed=3, n_samples=120, change=60, jump=2.0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_samples, 1))
    y = 1.0 + 0.5 * X[:, 0] + np.where(np.arange(1, n_samples + 1) > change, jump, 0.0) + rng.normal(size=n_samples)
    return X, y


def test_break_intervals_choose_bai_for_sse_without_overlap_and_clip():
    X, y = shifted_series()
    model = GroupedRegressor(p=1, n=0, objective="sse", search="exact").fit(X, y)
    report = break_intervals(model, X, y)
    assert report.method == "bai" and len(report.intervals) == 1
    interval = report.intervals[0]
    assert 1 <= interval.lower <= interval.brk <= interval.upper <= len(y) - 1
    assert interval.to_dict() == {
        "break": interval.brk,
        "lower": interval.lower,
        "upper": interval.upper,
        "level": 0.95,
        "method": "bai",
    }
    with pytest.raises(InputError, match="Bai"):
        break_intervals(GroupedRegressor(p=1, n=3, search="exact").fit(X, y), X, y, method="bai")


def test_bootstrap_is_deterministic_and_contains_the_estimate():
    X, y = shifted_series()
    model = GroupedRegressor(p=1, n=3, objective="sae", search="exact").fit(X, y)
    settings = dict(n=3, c=3.0, objective="sae", fit_intercept=True, n_boot=30, seed=11)
    first = bootstrap_break_intervals(X, y, model.breaks_, **settings)
    second = bootstrap_break_intervals(X, y, model.breaks_, **settings)
    assert np.array_equal(first.replicates, second.replicates)
    assert first.intervals == second.intervals and first.search == "exact"
    for interval, brk in zip(first.intervals, model.breaks_):
        assert interval.method == "bootstrap" and interval.lower <= brk <= interval.upper
    other = bootstrap_break_intervals(X, y, model.breaks_, **{**settings, "seed": 12})
    assert not np.array_equal(first.replicates, other.replicates)


def test_percentile_interval_takes_outer_order_statistics_and_keeps_the_estimate():
    replicates = np.array([[50]] * 10 + [[52]] * 80 + [[56]] * 10)
    (interval,) = percentile_intervals([52], replicates, 0.7, 100)
    assert (interval.lower, interval.upper) == (52, 52)
    (interval,) = percentile_intervals([52], replicates, 0.9, 100)
    assert (interval.lower, interval.upper) == (50, 56)
    (interval,) = percentile_intervals([49], replicates, 0.7, 100)  # widened to hold the estimate
    assert (interval.lower, interval.upper) == (49, 52)
    (interval,) = percentile_intervals([3], np.array([[1], [2], [99]]), 0.99, 100)
    assert (interval.lower, interval.upper) == (1, 99)


def test_block_resample_keeps_blocks_of_consecutive_residuals():
    residuals = np.arange(100.0)
    series = block_resample(residuals, 10, np.random.default_rng(0))
    assert len(series) == 100
    for start in range(0, 100, 10):
        assert np.all(np.diff(series[start : start + 10]) == 1.0)


def test_fit_prints_and_writes_bai_intervals(tmp_path, capsys):
    data = ROOT / "datasets" / "synthetic_cycle.csv"
    out = tmp_path / "out"
    args = ["fit", "--data", str(data), "--temps", "T1,T2", "--p", "2", "--search", "exact", "--quiet"]
    args += ["--objective", "sse", "--n", "0", "--out", str(out), "--json", str(tmp_path / "fit.json")]
    assert main(args) == 0
    report = capsys.readouterr().out
    result = json.loads((tmp_path / "fit.json").read_text())
    intervals = result["break_intervals"]
    assert [i["break"] for i in intervals] == result["breaks"]
    assert all(i["method"] == "bai" and i["level"] == 0.95 for i in intervals)
    assert "break 95 % CI" in report and "Bai (1997)" in report
    for interval in intervals:
        if interval["lower"] is not None:
            assert f"[{interval['lower']}, {interval['upper']}]" in report
    assert (out / "fit.png").stat().st_size > 10_000


def test_fit_bootstrap_option(tmp_path, capsys):
    data = ROOT / "datasets" / "synthetic_cycle.csv"
    args = ["fit", "--data", str(data), "--temps", "T1,T2", "--p", "1", "--search", "exact", "--quiet"]
    args += ["--intervals", "bootstrap", "--level", "0.9", "--bootstrap", "20", "--out", str(tmp_path / "o")]
    assert main([*args[:-1], str(tmp_path / "few"), "--level", "0.95"]) == 2  # tails of 2.5 % need 40 refits
    assert "--bootstrap 20: a 95 % interval needs at least 40 refits" in capsys.readouterr().err
    assert not (tmp_path / "few").exists()
    assert main([*args, "--json", "-"]) == 0
    printed = capsys.readouterr().out
    result = json.loads(printed[: printed.rindex("}") + 1])
    (interval,) = result["break_intervals"]
    assert interval["method"] == "bootstrap" and interval["lower"] <= interval["break"] <= interval["upper"]


def test_rule_of_thumb_flags_overlapping_and_wide_intervals():
    from groupfit.inference import weak_breaks
    from groupfit.inference.break_intervals import BreakInterval

    frame, y = example("nile")
    rows = [r for r in EXAMPLES["nile"]["intervals"] if r["m"] == 4 and r["het"]]
    intervals = bai_intervals(frame.to_numpy(), y, [r["break"] for r in rows])
    weak = weak_breaks(intervals, len(y))
    assert 28 not in weak  # the Aswan dam: [25, 31], clear of everything
    # 45 [4, 121] and 68 [43, 107] overlap narrower neighbours; 83 [58, 95] spans more than its 15- and 17-year groups
    assert set(weak) == {45, 68, 83} and "overlaps" in weak[45] and "overlaps" in weak[68] and "spans" in weak[83]
    rows = [r for r in EXAMPLES["nile"]["intervals"] if r["m"] == 2 and r["het"]]
    two = bai_intervals(frame.to_numpy(), y, [r["break"] for r in rows])
    assert list(weak_breaks(two, len(y))) == [83]  # [33, 130] over a last group of 17 years
    lone = [BreakInterval(50, 30, 70, 0.95, "bai")]
    assert "spans" in weak_breaks(lone, 100)[50]
    assert weak_breaks([BreakInterval(50, 45, 55, 0.95, "bai")], 100) == {}
    assert weak_breaks([BreakInterval(50, None, None, 0.95, "bai")], 100) == {}


def test_compare_prints_intervals_next_to_the_breaks_and_writes_bands(tmp_path, capsys):
    """compare with the sse objective and n = 0: Bai's intervals for every p, bands in the figures."""
    config = (ROOT / "configs" / "default.toml").read_text()
    config = config.replace('"../datasets/', f'"{ROOT.as_posix()}/datasets/')
    config = config.replace("n = 3\n", "n = 0\n").replace('objective = "sae"', 'objective = "sse"')
    path = tmp_path / "sse0.toml"
    path.write_text(config)
    out = tmp_path / "out"
    assert main(["compare", str(path), "--pmax", "2", "--quiet", "--out", str(out), "--json", str(out / "c.json")]) == 0
    report = capsys.readouterr().out
    result = json.loads((out / "c.json").read_text())
    assert set(result["break_intervals"]) == {"1", "2"}
    for p, intervals in result["break_intervals"].items():
        row = next(r for r in result["rows"] if r["model"] == "grouped" and r["p"] == int(p))
        assert [i["break"] for i in intervals] == row["breaks"]
        assert all(i["method"] == "bai" for i in intervals)
        first = intervals[0]
        assert f"{first['break']} [{first['lower']}, {first['upper']}]" in report
    assert "break intervals: Bai (1997)" in report
    assert (out / "compare_paper_cycle.png").stat().st_size > 10_000


def test_auto_leaves_the_bootstrap_out_before_a_refit_when_the_fits_own_search_says_it_is_too_slow(monkeypatch):
    X, y = shifted_series(n_samples=800, change=400)
    assert not exact_is_cheap(len(y), "sae")  # the refits search by the GA, as the fit did
    model = GroupedRegressor(p=1, n=3, objective="sae", search="ga").fit(X, y)

    def refuse(*args, **kwargs):
        raise AssertionError("no refit should start")

    monkeypatch.setattr("groupfit.inference.bootstrap_break_intervals", refuse)
    model.search_["seconds"] = 0.1  # 200 refits of it: 20 s, over a budget of 5 s
    report = break_intervals(model, X, y, n_boot=200, budget_s=5.0)
    assert report.intervals == [] and report.detail.startswith("not computed")
    assert report.seconds == pytest.approx(20.0)
    with pytest.raises(AssertionError, match="no refit"):  # asked for by name: run whatever it costs
        break_intervals(model, X, y, method="bootstrap", n_boot=200, budget_s=5.0)
    model.search_["seconds"] = 0.001  # 0.2 s: within the budget, so the bootstrap starts
    with pytest.raises(AssertionError, match="no refit"):
        break_intervals(model, X, y, n_boot=200, budget_s=5.0)
    small_X, small_y = shifted_series()  # cheap exact refits: the bootstrap's own projection decides
    small = GroupedRegressor(p=1, n=3, objective="sae", search="ga").fit(small_X, small_y)
    small.search_["seconds"] = 0.1
    with pytest.raises(AssertionError, match="no refit"):
        break_intervals(small, small_X, small_y, n_boot=200, budget_s=5.0)


@pytest.mark.parametrize(
    "options, message",
    [
        (["--intervals", "none", "--bootstrap", "50"], "--bootstrap: --intervals none computes no interval"),
        (["--intervals", "none", "--level", "0.9"], "--level: --intervals none computes no interval"),
        (
            ["--intervals", "bai", "--objective", "sse", "--n", "0", "--block", "3"],
            "--block: an option of the bootstrap",
        ),
        (["--intervals", "bootstrap", "--homoskedastic"], "--homoskedastic: an option of Bai's interval"),
    ],
)
def test_an_interval_option_the_method_does_not_read_is_refused(tmp_path, capsys, options, message):
    data = ROOT / "datasets" / "synthetic_cycle.csv"
    args = ["fit", "--data", str(data), "--temps", "T1,T2", "--p", "1", "--search", "exact", *options]
    assert main([*args, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "o").exists()
