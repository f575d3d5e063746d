"""``groupfit simulate`` on a lumped scenario: every bad value is one line, exit status 2 and no file.

Each case is ``configs/synthetic_cycle.toml`` with one line changed, run through
``groupfit.cli.main`` in this process as ``tests/test_bad_inputs.py``'s fast
lane does.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = (ROOT / "configs" / "synthetic_cycle.toml").read_text(encoding="utf-8")


def with_line(start: str, replacement: str) -> str:
    """The shipped lumped scenario with its line beginning ``start`` replaced by ``replacement``."""
    lines = SHIPPED.splitlines()
    matches = [k for k, line in enumerate(lines) if line.startswith(start)]
    assert len(matches) == 1, start
    lines[matches[0]] = replacement
    return "\n".join(lines) + "\n"


def simulate(tmp_path: Path, capsys, text: str) -> tuple[int, list[str], list[str]]:
    """Run ``simulate`` on ``text``: the status, stderr's lines and the files in ``tmp_path`` besides the config."""
    config = tmp_path / "scenario.toml"
    config.write_text(text, encoding="utf-8")
    capsys.readouterr()
    status = main(["simulate", str(config), "-o", str(tmp_path / "run.csv"), "--quiet"])
    written = sorted(path.name for path in tmp_path.iterdir() if path != config)
    return status, capsys.readouterr().err.strip().splitlines(), written


BAD_VALUES = [
    pytest.param("period_s", "period_s = nan", "'period_s'", "nan", id="period nan"),
    pytest.param("period_s", "period_s = inf", "'period_s'", "inf", id="period inf"),
    pytest.param("period_s", "period_s = 0.0", "'period_s'", "0.0", id="period zero"),
    pytest.param("period_s", "period_s = 1e9", "'period_s'", "1000000000.0", id="time axis beyond plausible"),
    pytest.param("ambient_c", "ambient_c = nan", "'ambient_c'", "nan", id="ambient nan"),
    pytest.param("ambient_c", "ambient_c = 1e308", "'ambient_c'", "1e+308", id="ambient implausible"),
    pytest.param("noise_c", "noise_c = nan", "'noise_c'", "nan", id="noise nan"),
    pytest.param("noise_c", "noise_c = -1", "'noise_c'", "-1", id="noise negative"),
    pytest.param("noise_c", "noise_c = 1e300", "'noise_c'", "1e+300", id="noise wider than any reading"),
    pytest.param("noise_c", "noise_c = 100.0", "'noise_c'", "100.0", id="noise takes readings out of range"),
    pytest.param("T1 ", "T1 = [-500.0, 9.0]", "'sensors.T1'", "-500.0", id="time constant negative"),
    pytest.param("T1 ", "T1 = [0.0, 9.0]", "'sensors.T1'", "0.0", id="time constant zero"),
    pytest.param("T1 ", "T1 = [500.0, -9.0]", "'sensors.T1'", "-9.0", id="gain negative"),
    pytest.param("T1 ", "T1 = [500.0, 1e6]", "'sensors.T1'", "1000000.0", id="gain beyond plausible"),
    pytest.param("T1 ", "T1 = 5", "'sensors.T1'", "got 5", id="sensor not a pair"),
    pytest.param("T1 ", "T1 = [500.0, 9.0, 1.0]", "'sensors.T1'", "[500.0, 9.0, 1.0]", id="sensor triple"),
    pytest.param("T1 ", "error_um = [500.0, 9.0]", "'sensors.error_um'", "reserved", id="sensor named error_um"),
    pytest.param("T1 ", "time_s = [500.0, 9.0]", "'sensors.time_s'", "reserved", id="sensor named time_s"),
    pytest.param("T1 ", "spindle_on = [500.0, 9.0]", "'sensors.spindle_on'", "reserved", id="sensor named spindle"),
    pytest.param("schedule", "schedule = []", "'schedule'", "[]", id="schedule empty"),
    pytest.param("schedule", "schedule = [[3000.0]]", "'schedule'", "[3000.0]", id="schedule step of one"),
    pytest.param("schedule", 'schedule = [["a", 1.0]]', "'schedule'", "['a', 1.0]", id="schedule step text"),
    pytest.param("schedule", "schedule = [[3000.0, -1.0]]", "'schedule'", "-1", id="schedule heat negative"),
    pytest.param("schedule", "schedule = [[0.0, 1.0]]", "'schedule'", "0.0", id="schedule duration zero"),
    pytest.param("schedule", "schedule = [[3000.0, 1e4]]", "'sensors.T1'", "10000.0", id="heat beyond for T1"),
    pytest.param("seed", "seed = -1", "'seed'", "-1", id="seed negative"),
    pytest.param("seed", "seed = 1.5", "'seed'", "1.5", id="seed fractional"),
    pytest.param("n_samples", "n_samples = 100000000000", "'n_samples'", "100000000000", id="samples too many"),
    pytest.param("n_samples", "n_samples = 1", "'n_samples'", "1", id="samples one"),
    pytest.param("kind", 'kind = "lumpy"', "'kind'", "lumpy", id="kind unknown"),
    pytest.param("seed", "seed = 0\nwobble = 3", "wobble", "wobble", id="key unknown"),
]


@pytest.mark.parametrize(("start", "replacement", "key", "value"), BAD_VALUES)
def test_a_bad_lumped_value_is_one_line_naming_file_key_and_value_and_writes_nothing(
    tmp_path, capsys, start, replacement, key, value
):
    status, lines, written = simulate(tmp_path, capsys, with_line(start, replacement))
    assert status == 2
    assert len(lines) == 1, lines
    assert "scenario.toml" in lines[0] and key in lines[0] and value in lines[0], lines[0]
    assert written == []


def test_too_many_samples_says_the_cap_and_what_to_use(tmp_path, capsys):
    _, lines, _ = simulate(tmp_path, capsys, with_line("n_samples", "n_samples = 100000000000"))
    assert "10,000,000 sub-steps" in lines[0] and "at most 1,000,000 samples" in lines[0]


def test_a_heat_beyond_the_plausible_error_names_the_schedule(tmp_path, capsys):
    unheated_sensor = SHIPPED[: SHIPPED.index("[sensors]")] + "[sensors]\nT1 = [500.0, 0.0]\n"
    text = unheated_sensor.replace("[21000.0, 1.0]", "[21000.0, 1e4]")
    status, lines, written = simulate(tmp_path, capsys, text)
    assert status == 2 and written == [] and len(lines) == 1
    assert "'schedule'" in lines[0] and "10000.0" in lines[0] and "µm" in lines[0], lines[0]


@pytest.mark.parametrize("text", ["", "# a scenario still to be written\n"], ids=["empty", "comments only"])
def test_an_empty_scenario_is_refused_not_run_as_the_headstock(tmp_path, capsys, text):
    status, lines, written = simulate(tmp_path, capsys, text)
    assert status == 2 and written == []
    assert len(lines) == 1 and "scenario.toml" in lines[0] and "empty" in lines[0] and "kind" in lines[0]


def test_a_valid_lumped_scenario_still_simulates_at_its_period_from_its_ambient(tmp_path, capsys):
    text = with_line("period_s", "period_s = 50.0")
    text = text.replace("ambient_c = 20.0", "ambient_c = 23.5").replace("noise_c = 0.02", "noise_c = 0.0")
    text = text.replace("schedule = [[3000.0, 1.0]", "schedule = [[1000.0, 0.0], [3000.0, 1.0]")
    status, lines, written = simulate(tmp_path, capsys, text)
    assert status == 0, lines
    assert written == ["run.csv", "run.png"]
    frame = pd.read_csv(tmp_path / "run.csv")
    assert list(frame.columns) == ["time_s", "T1", "T2", "T3", "T4", "error_um", "spindle_on"]
    assert len(frame) == 300
    assert np.allclose(np.diff(frame["time_s"]), 50.0)
    idle = frame["time_s"] <= 1000.0  # the first step is off: nothing has heated the sensors yet
    assert (frame.loc[idle, ["T1", "T2", "T3", "T4"]] == 23.5).all().all()
    assert frame["T1"].iloc[-1] > 23.5 + 5.0


@pytest.mark.parametrize("name", ["run.parquet", "run.xlsx", "run.json", "run.mat"])
def test_a_data_set_named_as_another_format_is_refused_before_simulating(tmp_path, capsys, name):
    """simulate writes CSV text: under a .parquet (…) name no reader of that format could open the file."""
    (tmp_path / "scenario.toml").write_text(SHIPPED)
    assert main(["simulate", str(tmp_path / "scenario.toml"), "--out", str(tmp_path / name), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "as CSV text" in err[0] and "name a .csv file" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scenario.toml"]
