"""compare's AR(1) row and its [compare] settings on odd inputs, and a validation run logged in another column order."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

PAPER = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets" / "paper_cycle.csv"


def split_recording(tmp_path: Path, reverse: bool) -> tuple[Path, Path]:
    """The paper cycle cut into a modelling file and the file that continues it (its columns reversed or not)."""
    frame = pd.read_csv(PAPER)
    cut = int(0.6 * len(frame))
    first, rest = tmp_path / "first.csv", tmp_path / ("rest_reversed.csv" if reverse else "rest.csv")
    frame.iloc[:cut].to_csv(first, index=False)
    following = frame.iloc[cut:]
    (following[following.columns[::-1]] if reverse else following).to_csv(rest, index=False)
    return first, rest


def compared(tmp_path: Path, *args: str) -> dict:
    out = tmp_path / "c.json"
    assert main(["compare", *args, "--pmax", "1", "--quiet", "--json", str(out), "--out", str(tmp_path / "f")]) == 0
    return json.loads(out.read_text())


def test_a_continuing_file_in_another_column_order_is_compared_as_the_same_continuation(tmp_path, capsys):
    first, rest = split_recording(tmp_path, reverse=False)
    _, reversed_rest = split_recording(tmp_path, reverse=True)
    plain = compared(tmp_path, "--data", str(first), "--validate", str(rest))
    assert "rest continues first" in capsys.readouterr().out
    other = compared(tmp_path, "--data", str(first), "--validate", str(reversed_rest))
    assert "rest_reversed continues first" in capsys.readouterr().out
    before = {r["model"]: r["rms_um"] for r in plain["rows"] if r["run"] == "rest"}
    after = {r["model"]: r["rms_um"] for r in other["rows"] if r["run"] == "rest_reversed"}
    assert set(before) == set(after) and len(before) >= 3
    for model, rms in before.items():
        assert after[model] == pytest.approx(rms, rel=1e-12)


def test_a_heat_column_that_moves_like_a_measurement_leaves_the_ar1_model_out_with_the_reason(tmp_path, capsys):
    frame = pd.read_csv(PAPER)
    frame["power_kW"] = np.round(frame["speed_rpm"] / 1000 + np.random.default_rng(0).random(len(frame)), 3)
    path = tmp_path / "power.csv"
    frame.to_csv(path, index=False)
    config = tmp_path / "c.toml"
    config.write_text('[compare]\nheat = "power_kW"\n')
    result = compared(tmp_path, str(config), "--data", str(path))
    assert result["ar1"] is None and result["expected_next_run"]["ar1"] is None
    assert "AR(1): left out (its heat column 'power_kW' moves like a measurement" in capsys.readouterr().out


@pytest.mark.parametrize(
    "lines, message",
    [
        ('ar1_fit = "free-run"', "config key 'compare.ar1_fit': must be one of one_step, free_run"),
        ('ar1_scaling = "bogus"', "config key 'compare.ar1_scaling': must be one of heat_law, rise"),
        ("heat_exponent = 50.0", "config key 'compare.heat_exponent': expected a number in (0, 4]"),
        ('ar1_scaling = "rise"\nrise_sensor = "T1"\nrise_window_s = -60', "config key 'compare.rise_window_s'"),
        ('ar1_scaling = "rise"\nrise_sensor = "time_s"', "rise sensor 'time_s' is the run's time"),
        ('ar1_scaling = "rise"\nrise_sensor = "error_um"', "rise sensor 'error_um' is the run's error"),
        ('ar1_scaling = "rise"\nrise_sensor = "speed_rpm"', "rise sensor 'speed_rpm' is named as a speed"),
    ],
)
def test_odd_ar1_settings_are_refused_naming_the_key_or_the_column(tmp_path, capsys, lines, message):
    config = tmp_path / "c.toml"
    config.write_text(f'[compare]\nheat = "speed_rpm"\n{lines}\n')
    args = ["compare", str(config), "--data", str(PAPER), "--pmax", "1", "--quiet", "--out", str(tmp_path / "f")]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "f").exists()


def test_the_rise_sensor_taken_by_default_is_named(tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text('[compare]\nheat = "speed_rpm"\nar1_scaling = "rise"\n')
    result = compared(tmp_path, str(config), "--data", str(PAPER))
    assert any("early rise of T1, the first input" in note for note in result["notes"])
