"""A stage without progress of its own says it is still running, so a long log is never silent for minutes."""

import contextlib
import io
import re
import time
from pathlib import Path

import numpy as np
import pytest

from groupfit import running
from groupfit.cli import main
from groupfit.comparison_path import grouped_path
from groupfit.search.base import GASettings, SearchSettings

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"


def lines_of(stream: io.StringIO) -> list[str]:
    return stream.getvalue().splitlines()


def test_a_long_stage_says_it_runs_and_when_it_is_done():
    stream = io.StringIO()
    with running.stage("next-run estimate", stream=stream, first=0.05, every=0.05):
        time.sleep(0.4)
    lines = lines_of(stream)
    assert len(lines) >= 3, lines
    assert all(re.fullmatch(r"progress next-run estimate: running for \d+ s", line) for line in lines[:-1])
    assert re.fullmatch(r"progress next-run estimate: done after \d+ s", lines[-1])


def test_a_quick_stage_and_a_quiet_one_say_nothing():
    quick, quiet = io.StringIO(), io.StringIO()
    with running.stage("quick", stream=quick, first=5.0):
        pass
    with running.stage("quiet", stream=quiet, enabled=False, first=0.01, every=0.01):
        time.sleep(0.1)
    assert quick.getvalue() == "" and quiet.getvalue() == ""


def test_a_failing_stage_raises_its_error_and_stops_telling():
    stream = io.StringIO()
    with pytest.raises(KeyboardInterrupt), running.stage("loading", stream=stream, first=0.02, every=0.02):
        time.sleep(0.1)
        raise KeyboardInterrupt
    said = len(lines_of(stream))
    time.sleep(0.1)
    assert len(lines_of(stream)) == said and lines_of(stream)[-1].startswith("progress loading: done after")


@pytest.fixture
def entered(monkeypatch):
    names = []

    @contextlib.contextmanager
    def recorded(name, **kwargs):
        names.append(name)
        yield

    monkeypatch.setattr(running, "stage", recorded)
    return names


def test_fit_compare_and_replay_run_their_long_stages_as_stages(tmp_path, entered):
    data = str(DATASETS / "paper_cycle.csv")
    assert main(["fit", "--data", data, "--quiet", "--out", str(tmp_path / "f")]) == 0
    assert {"loading", "reference choice", "next-run estimate", "held-out check", "recalibration"} <= set(entered)
    entered.clear()
    assert main(["compare", "--data", data, "--pmax", "1", "--quiet", "--out", str(tmp_path / "c")]) == 0
    assert {"loading", "break intervals", "next-run estimate"} <= set(entered)
    entered.clear()
    model = str(tmp_path / "f" / "model.json")
    assert main(["replay", model, "--data", data, "--probe-every", "600", "--out", str(tmp_path / "r")]) == 0
    assert entered == ["loading", "replay", "writing the outputs"]
    entered.clear()
    assert main(["fit", "--model", "ar1", "--data", data, "--heat", "speed_rpm", "--out", str(tmp_path / "a")]) == 0
    assert entered == ["next-run estimate"]


def test_compares_grouped_fits_report_their_search_per_p_and_the_stage_from_its_start():
    rng = np.random.default_rng(2)
    X = np.cumsum(rng.normal(0, 0.1, (240, 2)), axis=0)
    y = X @ [1.0, -2.0] + np.where(np.arange(240) < 120, 0.0, 2.0) + rng.normal(0, 0.05, 240)
    calls = []
    search = SearchSettings(
        method="ga", seed=1, ga=GASettings(population_size=20, max_generations=15, stall_generations=5)
    )
    grouped_path(
        X, y, 2, n=3, c=3.0, objective="sse", fit_intercept=True, search=search, certified=False,
        progress=lambda stage, fraction: calls.append((stage, fraction)),
    )  # fmt: skip
    assert calls[0] == ("grouped", 0.0)
    assert [f for stage, f in calls if stage == "grouped"] == [0.0, 0.5, 1.0]  # the projection's contract
    for p in (1, 2):
        fractions = [f for stage, f in calls if stage == f"ga p = {p}"]
        assert len(fractions) > 1 and fractions[-1] == 1.0 and fractions == sorted(fractions)
