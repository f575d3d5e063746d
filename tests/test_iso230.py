"""ISO 230-2 evaluation against a hand computation and an independent numpy computation of its definitions."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.iso230 import load_runs, simulate_runs

R2 = math.sqrt(2.0)


def tiny_runs() -> pd.DataFrame:
    """Two targets, two runs each way, rows in the cycle's order (up 0 → 10, down 10 → 0)."""
    rows = [
        (1, "+", 0.0, 1.0),
        (1, "+", 10.0, 2.0),
        (1, "-", 10.0, 0.0),
        (1, "-", 0.0, -1.0),
        (2, "up", 0.0, 3.0),
        (2, "up", 10.0, 2.0),
        (2, "down", 10.0, 2.0),
        (2, "down", 0.0, -1.0),
    ]
    return pd.DataFrame(rows, columns=["run", "direction", "target_mm", "deviation_um"])


def test_a_tiny_example_matches_the_hand_computation():
    # x↑ = (2, 2), x↓ = (-1, 1), B_i = (3, 1), s↑ = (√2, 0), s↓ = (0, √2)
    result = load_runs(tiny_runs())
    axis = result.axis()
    expected = {
        "B": 3.0,
        "B_mean": 2.0,
        "R_up": 4 * R2,
        "R_down": 4 * R2,
        "R": 3 + 2 * R2,  # at 0 mm: max(2√2 + 0 + 3, 4√2, 0)
        "E_up": 0.0,
        "E_down": 2.0,
        "E": 3.0,  # max(2, 2, -1, 1) - min(...)
        "M": 1.0,  # x = (0.5, 1.5)
        "A_up": 4 * R2,  # (2 + 2√2) - (2 - 2√2)
        "A_down": 4 * R2,  # (1 + 2√2) - (1 - 2√2)
        "A": 1 + 4 * R2,  # (2 + 2√2) - (1 - 2√2)
    }
    assert axis == pytest.approx(expected, abs=1e-12)
    positions = result.positions()
    assert [p["R_um"] for p in positions] == pytest.approx([3 + 2 * R2, 4 * R2], abs=1e-12)
    assert [p["mean_um"] for p in positions] == pytest.approx([0.5, 1.5], abs=1e-12)


def by_hand(frame: pd.DataFrame) -> dict[str, float]:
    """ISO 230-2's axis parameters from the table with plain numpy, target by target."""
    targets = sorted(frame.target_mm.unique())
    up_mean, down_mean, up_s, down_s = [], [], [], []
    for p in targets:
        for sign, means, sds in (("+", up_mean, up_s), ("-", down_mean, down_s)):
            x = frame.deviation_um[(frame.target_mm == p) & (frame.direction == sign)].to_numpy()
            mean = x.sum() / len(x)
            means.append(mean)
            sds.append(math.sqrt(((x - mean) ** 2).sum() / (len(x) - 1)))
    xu, xd, su, sd = map(np.array, (up_mean, down_mean, up_s, down_s))
    b = xu - xd
    r_i = [max(2 * su[i] + 2 * sd[i] + abs(b[i]), 4 * su[i], 4 * sd[i]) for i in range(len(targets))]
    mean = (xu + xd) / 2
    return {
        "B": max(abs(b)),
        "B_mean": b.mean(),
        "R_up": max(4 * su),
        "R_down": max(4 * sd),
        "R": max(r_i),
        "E_up": xu.max() - xu.min(),
        "E_down": xd.max() - xd.min(),
        "E": max(xu.max(), xd.max()) - min(xu.min(), xd.min()),
        "M": mean.max() - mean.min(),
        "A_up": (xu + 2 * su).max() - (xu - 2 * su).min(),
        "A_down": (xd + 2 * sd).max() - (xd - 2 * sd).min(),
        "A": max((xu + 2 * su).max(), (xd + 2 * sd).max()) - min((xu - 2 * su).min(), (xd - 2 * sd).min()),
    }


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_simulated_standard_cycles_match_an_independent_computation(seed):
    frame = simulate_runs(np.linspace(0.0, 630.0, 8) + [0, 3, 11, 2, 7, 13, 5, 0], seed=seed)
    assert len(frame) == 8 * 5 * 2
    assert load_runs(frame).axis() == pytest.approx(by_hand(frame), abs=1e-12)


def test_the_simulator_is_deterministic_and_its_reversal_and_repeatability_are_recovered():
    targets = np.linspace(0.0, 500.0, 6)
    assert simulate_runs(targets, seed=4).equals(simulate_runs(targets, seed=4))
    assert not simulate_runs(targets, seed=4).equals(simulate_runs(targets, seed=5))
    exact = load_runs(simulate_runs(targets, noise_um=0.0, drift_um_per_run=0.0, reversal_um=4.0))
    axis = exact.axis()
    assert axis["B"] == pytest.approx(4.0) and axis["B_mean"] == pytest.approx(4.0)
    assert axis["R"] == pytest.approx(4.0) and axis["R_up"] == pytest.approx(0.0, abs=1e-12)
    assert axis["A"] == pytest.approx(axis["E"]) and axis["M"] == pytest.approx(axis["E"] - 4.0)
    noisy = load_runs(simulate_runs(targets, repeats=200, noise_um=0.5, drift_um_per_run=0.0, seed=3)).axis()
    assert noisy["R_up"] == pytest.approx(4 * 0.5, rel=0.25)  # 4 s with s the noise
    assert noisy["B_mean"] == pytest.approx(4.0, abs=0.1)


def test_the_verb_prints_writes_json_and_a_figure(tmp_path, capsys):
    frame = simulate_runs(np.linspace(0.0, 400.0, 5), seed=1)
    frame.to_csv(tmp_path / "runs.csv", index=False)
    code = main(["iso230", str(tmp_path / "runs.csv"), "--json", str(tmp_path / "r.json"), "--out", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["repeats"] == 5 and result["standard_cycle"] and result["targets"] == 5
    assert result["axis_um"] == pytest.approx(by_hand(frame), abs=1e-12)
    assert f"R {result['axis_um']['R']:.3f}" in out and (tmp_path / "iso230.png").stat().st_size > 0


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda f: f.assign(direction=f.direction.where(f.index != 3, "sideways")), "row 4, column 'direction'"),
        (
            lambda f: f.drop(index=[2]),
            "row 6, column 'target_mm': target 10 mm is approached 1 time(s) in the - direction, up to 2 elsewhere",
        ),
        (
            lambda f: f[f.direction.isin(["+", "up"])],
            "rows 1, 3, column 'target_mm': target 0 mm is never approached in the negative direction",
        ),
        (
            lambda f: f.assign(target_mm=f.target_mm.where(f.index != 2, 10.0000001)),
            "row 3, column 'target_mm': target 10.0000001 mm is never approached in the positive direction "
            "(1e-07 mm from target 10 mm: a mistyped target?)",
        ),
        (lambda f: f.drop(columns="deviation_um"), "column 'deviation_um' not found"),
        (lambda f: f.assign(target_mm=f.target_mm.astype(object).where(f.index != 1, "x")), "target_mm"),
    ],
)
def test_bad_runs_are_refused_with_one_line(tmp_path, capsys, change, message):
    frame = tiny_runs()
    frame["direction"] = frame.direction.replace({"up": "+", "down": "-"})
    change(frame).to_csv(tmp_path / "bad.csv", index=False)
    assert main(["iso230", str(tmp_path / "bad.csv"), "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.csv" in err[0] and message in err[0]
    assert not (tmp_path / "r.json").exists()
