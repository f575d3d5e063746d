"""``compare --probe-every … --tolerance UM``: per model the longest check interval that meets a tolerance."""

import json

import numpy as np
import pytest

import groupfit.probe_intervals as probe_intervals
from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.probe_intervals import interval_plan, interval_table, parse_intervals

PERIOD_S = 60.0
INTERVALS_S = (900.0, 1800.0, 3600.0, 7200.0)


def held_by_loop(residual: np.ndarray, every: int) -> np.ndarray:
    """The offset hold written out sample by sample: the residual less the last check's, checks after every
    ``every`` samples from the first interval on."""
    out, offset = np.empty_like(residual), 0.0
    for i, r in enumerate(residual):
        out[i] = r - offset
        if (i + 1) % every == 0:
            offset = r
    return out


def brute_force_plan(residuals: dict, tolerance: float) -> dict:
    plan = {}
    for model in {m for m, _ in residuals}:
        runs = [r for (m, _), r in residuals.items() if m == model]
        meeting = [
            t
            for t in INTERVALS_S
            if all(np.sqrt(np.mean(held_by_loop(r, int(t / PERIOD_S)) ** 2)) <= tolerance for r in runs)
        ]
        quiet = all(np.sqrt(np.mean(r**2)) <= tolerance for r in runs)
        plan[model] = {"longest_interval_s": max(meeting) if meeting else None, "without_checks": quiet}
    return plan


@pytest.mark.parametrize("tolerance", [0.05, 0.3, 0.8, 1.5, 3.0, 12.0])
def test_the_plan_is_the_longest_interval_that_meets_the_tolerance_on_every_run(tolerance):
    rng = np.random.default_rng(7)
    hours = np.arange(24 * 60) * PERIOD_S / 3600.0
    residuals = {
        ("offset", "a"): 5.0 + 0.05 * rng.standard_normal(hours.size),  # a hold takes it whole
        ("offset", "b"): -4.0 + 0.05 * rng.standard_normal(hours.size),
        ("drift", "a"): 0.8 * hours + 0.05 * rng.standard_normal(hours.size),  # stale by slope × interval
        ("drift", "b"): 1.6 * hours,
        ("floor", "a"): 0.2 * rng.standard_normal(hours.size),  # checks only carry noise
        ("floor", "b"): 0.2 * rng.standard_normal(hours.size),
    }
    errors = {run: np.zeros(hours.size) for run in ("a", "b")}
    predictions = {run: {m: -r for (m, k), r in residuals.items() if k == run} for run in errors}
    table = interval_table(errors, predictions, {"a": PERIOD_S, "b": PERIOD_S}, INTERVALS_S)
    plan = interval_plan(table, tolerance)
    assert plan["tolerance_um"] == tolerance
    assert plan["models"] == brute_force_plan(residuals, tolerance)


def test_compare_prints_and_writes_the_plan(tmp_path, capsys):
    base = ["compare", "--pmax", "1", "--probe-every", "15m,30m,1h,2h", "--out", str(tmp_path / "cmp"), "--quiet"]
    assert main([*base, "--json", str(tmp_path / "a.json")]) == 0
    table = json.loads((tmp_path / "a.json").read_text())["probe_intervals"]
    assert "plan" not in table
    values = sorted(v for row in table["rows"] for v in row["rms_um"])
    tolerance = float(np.median(values))
    capsys.readouterr()
    assert main([*base, "--tolerance", f"{tolerance!r}", "--json", str(tmp_path / "b.json")]) == 0
    report = capsys.readouterr().out
    planned = json.loads((tmp_path / "b.json").read_text())["probe_intervals"]["plan"]
    assert planned["models"] == brute_force_from_table(table, tolerance)
    assert f"the longest check interval with RMS ≤ {tolerance:g} µm on every run" in report
    for model, entry in planned["models"].items():
        if entry["longest_interval_s"] is not None and not entry["without_checks"]:
            minutes = entry["longest_interval_s"] / 60
            shown = f"{minutes / 60:g} h" if minutes >= 60 else f"{minutes:g} min"
            assert any(line.split()[:1] == [model] and line.endswith(f"every {shown}") for line in report.splitlines())


def brute_force_from_table(table: dict, tolerance: float) -> dict:
    plan = {}
    for model in {row["model"] for row in table["rows"]}:
        rows = [row for row in table["rows"] if row["model"] == model]
        ok = [t for k, t in enumerate(table["intervals_s"]) if all(row["rms_um"][k] <= tolerance for row in rows)]
        plan[model] = {
            "longest_interval_s": max(ok) if ok else None,
            "without_checks": all(row["rms_none_um"] <= tolerance for row in rows),
        }
    return plan


@pytest.mark.parametrize(
    "args, message",
    [
        (["--tolerance", "2"], "--tolerance needs --probe-every"),
        (["--probe-every", "30m", "--tolerance", "0"], "--tolerance '0': must be a finite number > 0"),
        (["--probe-every", "30m", "--tolerance=-1"], "--tolerance '-1': must be a finite number > 0"),
        (["--probe-every", "30m", "--tolerance", "two"], "--tolerance 'two': give the largest acceptable RMS error"),
        (["--probe-every", "30m,1e8"], "--probe-every: 1e+08 s is longer than"),
        (["--probe-every", "30m", "--probe-first", "1e8"], "--probe-first 1e+08: after the end of"),
    ],
)
def test_a_bad_tolerance_or_interval_is_refused_with_one_line(tmp_path, capsys, args, message):
    out = tmp_path / "cmp"
    assert main(["compare", "--pmax", "0", *args, "--out", str(out), "--json", str(tmp_path / "c.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists() and not (tmp_path / "c.json").exists()


def test_an_interval_given_twice_is_refused_in_any_unit():
    assert parse_intervals("5m,30m,2h") == [300.0, 1800.0, 7200.0]
    for text in ("30m,30m", "1800,30m", "0.5h,1800s"):
        with pytest.raises(InputError, match="repeats an interval given before \\(1800 s\\)"):
            parse_intervals(text)


def test_an_interval_shorter_than_a_sample_checks_every_sample_as_replay_does(tmp_path, capsys):
    out = tmp_path / "c.json"
    args = ["compare", "--pmax", "0", "--probe-every", "1s,100s", "--out", str(tmp_path / "cmp"), "--json", str(out)]
    assert main(args) == 0
    report = capsys.readouterr().out
    data = json.loads(out.read_text())
    rows = data["probe_intervals"]["rows"]
    assert rows and all(row["rms_um"][0] == row["rms_um"][1] != row["rms_none_um"] for row in rows)
    rounded = [note for note in data["data_notes"] if note.startswith("--probe-every 1 s: ")]
    assert len(rounded) == len({row["run"] for row in rows})  # one per validation run, whatever the models
    assert all(note.endswith("so its checks fall every 100 s (whole samples)") for note in rounded)
    assert all(f"note    {note}" in report for note in data["data_notes"])


def test_the_figure_puts_each_runs_unchecked_rms_at_none_with_its_own_marker(tmp_path, monkeypatch):
    figures = []
    monkeypatch.setattr(probe_intervals, "save_figure", lambda fig, path, dpi: figures.append(fig))
    rows = [
        {"model": model, "run": run, "rms_none_um": none, "rms_um": [0.5, 0.6]}
        for model, run, none in (("mlr", "a", 1.0), ("mlr", "b", 2.0), ("grouped1", "a", 3.0))
    ]
    probe_intervals.plot_intervals({"intervals_s": [900.0, 3600.0], "method": "offset hold", "rows": rows}, tmp_path)
    ax = figures[0].axes[0]
    assert [tick.get_text() for tick in ax.get_xticklabels()] == ["15 min", "1 h", "none"]
    at_none = ax.get_xticks()[-1]
    hollow = [line for line in ax.lines if line.get_markerfacecolor() == "none"]
    assert sorted(float(line.get_ydata()[0]) for line in hollow) == [1.0, 2.0, 3.0]
    assert all(float(line.get_xdata()[0]) == at_none for line in hollow)
    by_run = {float(line.get_ydata()[0]): line.get_marker() for line in hollow}
    assert by_run[1.0] == by_run[3.0] != by_run[2.0]  # one marker per run, whatever the model
