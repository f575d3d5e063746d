"""A log that names no column as a temperature: the inputs are the columns whose readings look like temperatures."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.default_columns import temperature_like_columns

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
GENERIC = {"T1": "frame_left", "T2": "spindle_nose", "T3": "bed", "T4": "motor", "T5": "column", "T6": "gantry"}


@pytest.fixture(scope="module")
def generic() -> pd.DataFrame:
    """The shipped run as a logger without sensor names writes it, with other quantities beside."""
    frame = pd.read_csv(DATASETS / "paper_cycle.csv").rename(columns=GENERIC)
    rng = np.random.default_rng(0)
    frame["spindle_power_kW"] = frame["speed_rpm"] / 400.0 + rng.normal(0, 0.1, len(frame))
    frame["x_position"] = rng.uniform(0, 150, len(frame))
    frame["sample"] = np.arange(len(frame))
    frame["coolant_level"] = np.where(np.arange(len(frame)) < 300, 80.0, 60.0)
    return frame


def fitted(tmp_path: Path, frame: pd.DataFrame, *args) -> dict:
    path = tmp_path / "log.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / f"fit{len(args)}.json"
    assert main(["fit", "--data", str(path), "--quiet", "--json", str(out), "--out", str(tmp_path / "o"), *args]) == 0
    return json.loads(out.read_text())


def test_the_columns_that_read_like_temperatures_are_the_inputs(generic):
    assert temperature_like_columns(generic, exclude=("time_s", "error_um")) == list(GENERIC.values())


def test_fit_takes_them_with_a_note_and_fits_as_if_they_were_named(tmp_path, generic, capsys):
    found = fitted(tmp_path, generic)
    note = capsys.readouterr().out
    assert "no column is named as a temperature" in note and ", ".join(GENERIC.values()) in note
    named = fitted(tmp_path, generic, "--temps", ",".join(GENERIC.values()))
    assert found["temps"] == named["temps"] and found["p"] == named["p"]
    assert np.allclose(found["coefficients"], named["coefficients"], rtol=0, atol=1e-12)


def test_a_log_with_nothing_like_a_temperature_is_still_refused_in_one_line(tmp_path, generic, capsys):
    frame = generic.drop(columns=list(GENERIC.values()))
    path = tmp_path / "log.csv"
    frame.to_csv(path, index=False)
    assert main(["fit", "--data", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no temperature columns found" in err[0] and "--temps" in err[0]


def test_a_column_named_as_the_air_is_left_out_and_the_note_says_how_to_take_it(tmp_path, generic, capsys):
    frame = generic.copy()
    rng = np.random.default_rng(1)
    frame.insert(2, "chamber_t", frame["frame_left"] + 3.0 + rng.normal(0, 0.05, len(frame)))
    assert temperature_like_columns(frame, exclude=("time_s", "error_um"), air=True) == ["chamber_t", "T_amb"]
    found = fitted(tmp_path, frame)
    note = capsys.readouterr().out
    assert "chamber_t" not in found["temps"]
    listed = ",".join([*list(GENERIC.values())[:1], "chamber_t", *list(GENERIC.values())[1:]])
    assert f"chamber_t is named as the air and not an input: --temps {listed} takes it too" in note
    named = fitted(tmp_path, frame, "--temps", listed)
    assert "chamber_t" in named["temps"]
