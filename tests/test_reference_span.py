"""A next run on a day warmer than the modelling day: the reference column's own span is kept and checked."""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest
from support import independent_machine as machine

from groupfit.cli import main

GAINS = {"B": 1.0, "H": 2.0, "C": 1.5, "S": 3.0}
PROGRAMME = [(1.5, 1000), (2, 3000), (1, 0), (2, 2000), (1.5, 4000), (2, 0), (2, 1500)]


@lru_cache(maxsize=None)
def day(base_c: float, swing_k: float, seed: int) -> pd.DataFrame:
    """The same programme on a workshop day around ``base_c`` (the error over 20 °C: the parts' own heat)."""
    ambient = {"base_c": base_c, "daily_amplitude_k": swing_k}
    sim = machine.simulate(12, 60, speed=PROGRAMME, ambient=ambient, seed=seed)
    return machine.logged_run(sim, GAINS)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("days")
    paths = {}
    for name, base, swing, seed in (("model", 20.0, 1.0, 11), ("same", 20.0, 1.0, 12), ("warm", 24.0, 1.0, 13)):
        paths[name] = folder / f"{name}.csv"
        day(base, swing, seed).to_csv(paths[name], index=False)
    out = folder / "m"
    args = ["fit", "--data", str(paths["model"]), "--reference", "T_amb", "--p", "0", "--out", str(out), "--quiet"]
    assert main([*args, "--recalibrate", "none"]) == 0
    return paths, out / "model.json"


def replay(tmp_path, model, data, capsys) -> tuple[dict, str]:
    capsys.readouterr()
    out = tmp_path / f"{data.stem}.json"
    assert main(["replay", str(model), "--data", str(data), "--json", str(out)]) == 0
    return json.loads(out.read_text()), capsys.readouterr().out


def test_the_model_file_keeps_the_reference_columns_span(runs):
    paths, model = runs
    span = json.loads(model.read_text())["training"]["input_span"]
    ambient = pd.read_csv(paths["model"])["T_amb"]
    assert span["T_amb"] == [ambient.min(), ambient.max()]
    assert set(span) == {"T1", "T2", "T3", "T4", "T_amb"}


def test_a_warmer_day_is_said_to_leave_the_reference_and_the_advice_holds(tmp_path, runs, capsys):
    paths, model = runs
    data, printed = replay(tmp_path, model, paths["warm"], capsys)
    warm = pd.read_csv(paths["warm"])["T_amb"]
    entry = next(b for b in data["beyond_modelling_range"] if b["input"] == "T_amb")
    assert entry["reference"] and entry["samples"] == len(warm) and entry["run"] == [warm.min(), warm.max()]
    zero = next(note for note in data["notes"] if note.startswith("the residual is nearly a constant"))
    assert "while the reference T_amb the inputs are taken against reads" in zero and "--reference none" in zero
    assert f"T_amb {warm.min():.3g}..{warm.max():.3g} (modelled" in printed
    out = tmp_path / "none"
    fit = ["fit", "--data", str(paths["model"]), "--reference", "none", "--p", "0", "--out", str(out), "--quiet"]
    assert main([*fit, "--recalibrate", "none"]) == 0
    absolute, _ = replay(out, out / "model.json", paths["warm"], capsys)
    assert absolute["rms_um"] < 0.75 * data["rms_um"]  # the refit the note advises does better on that day


def test_a_day_at_the_modelling_level_stays_within_the_reference_span(tmp_path, runs, capsys):
    paths, model = runs
    data, _ = replay(tmp_path, model, paths["same"], capsys)
    modelled, same = (pd.read_csv(paths[name])["T_amb"] for name in ("model", "same"))
    assert same.min() < modelled.min()  # a little below the modelling day's air: within its own swing
    assert not any(b.get("reference") for b in data.get("beyond_modelling_range", []))
    assert not any("reference T_amb" in note for note in data.get("notes", []))
    assert np.isfinite(data["rms_um"])
