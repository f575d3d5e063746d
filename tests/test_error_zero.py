"""A next run whose error is measured from another zero than the modelling run's (a probe's absolute position
after re-homing): ``replay`` scores it as logged and names the constant offset; a run measured from the same zero,
or one the model misses by a bias of the size it expected, gets no such note. A run whose machine as a whole sits
at another level (a warm start) misses by a near constant too, and the note names that first."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.error_zero import EXPECTED_RATIO, SPREAD_RATIO, level_shift, zero_offset

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("zero")
    options = ["--p", "0", "--quiet", "--recalibrate", "none", "--out", str(out)]
    assert main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), *options]) == 0
    return out / "model.json"


def replayed(capsys, model: Path, frame: pd.DataFrame, path: Path) -> tuple[dict, str]:
    frame.to_csv(path, index=False)
    capsys.readouterr()
    assert main(["replay", str(model), "--data", str(path), "--json", "-"]) == 0
    captured = capsys.readouterr()
    return json.loads(captured.out), captured.err


@pytest.mark.parametrize("shift_um", [5000.0, -80000.0])
def test_a_next_run_from_another_zero_is_scored_as_logged_and_its_offset_named(model, tmp_path, capsys, shift_um):
    next_run = pd.read_csv(DATASETS / "validation_speed.csv")
    plain, _ = replayed(capsys, model, next_run, tmp_path / "plain.csv")
    assert "constant_offset_um" not in plain
    moved = next_run.assign(error_um=next_run.error_um + shift_um)
    shifted, report = replayed(capsys, model, moved, tmp_path / "shifted.csv")
    residual = np.array([s["residual_um"] for s in plain["samples"]], dtype=float)
    assert shifted["constant_offset_um"] == pytest.approx(np.nanmean(residual) + shift_um, abs=1e-6)
    assert shifted["rms_um"] == pytest.approx(np.sqrt(np.nanmean((residual + shift_um) ** 2)), rel=1e-9)
    assert "seems measured from another zero than the modelling run's" in report
    assert f"nearly a constant {shifted['constant_offset_um']:.4g} µm" in report


def test_an_offset_is_named_only_when_it_is_both_steady_and_far_beyond_the_expectation():
    rng = np.random.default_rng(0)
    noise = rng.normal(0.0, 1.0, 500)
    expected = 2.0
    far = EXPECTED_RATIO * expected * 1.5
    assert zero_offset(noise + far, expected)[0]["constant_offset_um"] == pytest.approx(far + noise.mean())
    assert zero_offset(noise + 3 * expected, expected) == ({}, [])  # a bias a next run may well show
    wandering = np.linspace(-1.0, 1.0, 500) * far * 2 / SPREAD_RATIO + far  # steady? no: it drifts widely
    assert zero_offset(wandering, expected) == ({}, [])
    assert zero_offset(noise + far, None) == ({}, []) and zero_offset(None, expected) == ({}, [])
    with_gaps = np.where(np.arange(500) % 7 == 0, np.nan, noise + far)
    assert zero_offset(with_gaps, expected)[0]["constant_offset_um"] == pytest.approx(np.nanmean(with_gaps))


def test_a_machine_warmer_as_a_whole_is_named_before_another_zero(model, tmp_path, capsys):
    next_run = pd.read_csv(DATASETS / "validation_speed.csv")
    sensors = [c for c in next_run.columns if c.startswith("T") and c[1:].isdigit()]
    plain, _ = replayed(capsys, model, next_run, tmp_path / "plain.csv")
    warm = next_run.assign(**{c: next_run[c] + 12.0 for c in sensors})  # every part 12 K warmer, the air as it was
    shifted, report = replayed(capsys, model, warm, tmp_path / "warm.csv")
    beyond = {b["input"]: b for b in shifted["beyond_modelling_range"]}
    wholly_above = [c for c in sensors if c in beyond and beyond[c]["run"][0] > beyond[c]["span"][1]]
    assert len(wholly_above) >= max(2, len(sensors) / 2)
    assert "constant_offset_um" in shifted and "constant_offset_um" not in plain
    named = report[report.index("nearly a constant") :]
    assert f"{', '.join(wholly_above)} read above their modelling ranges" in named
    assert named.index("warmer than on the modelling run") < named.index("another zero")


def test_a_level_shift_is_every_wholly_outside_input_on_one_side():
    def entry(name, span, run, reference=False):
        return {"input": name, "span": span, "run": run, "samples": 10, **({"reference": True} if reference else {})}

    above = [entry("T1", [20, 22], [25, 26]), entry("T2", [20, 21], [23, 24])]
    assert level_shift(above, 4) == ("above", above)
    assert level_shift(above, 5) is None  # two of five inputs: not the machine as a whole
    partly = entry("T3", [20, 30], [25, 31])  # outside on some samples only: neither side
    assert level_shift([*above, partly], 4) == ("above", above)
    below = [entry("T1", [20, 22], [15, 16]), entry("T2", [20, 21], [17, 18])]
    assert level_shift(below, 3) == ("below", below)
    assert level_shift([above[0], below[1]], 2) is None  # one warmer, one cooler: no level shift
    assert level_shift([above[0], entry("T_amb", [19, 20], [25, 26], reference=True)], 2) is None
