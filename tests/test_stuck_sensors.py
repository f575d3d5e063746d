"""A sensor stuck on one reading while the machine moves is named on loading; a coarse sensor resting on a
step, a quiet machine and a short flat stretch are not."""

import itertools
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.stuck_sensors import longest_unchanged, resolution, stuck_stretches

SHARED_TEST = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"


def brute_longest(values) -> int:
    """Length of the longest stretch of equal consecutive readings (NaN never equal)."""
    best = 0
    for _, group in itertools.groupby(range(len(values)), key=lambda i: values[i]):
        group = list(group)
        best = max(best, 1 if np.isnan(values[group[0]]) else len(group))
    return best


@pytest.mark.parametrize("seed", range(20))
def test_the_longest_unchanged_stretch_is_that_of_brute_force(seed):
    rng = np.random.default_rng(seed)
    values = rng.integers(0, 3, rng.integers(1, 60)).astype(float)
    values[rng.random(len(values)) < 0.1] = np.nan
    first, last = longest_unchanged(values)
    assert last - first + 1 == brute_longest(list(values))
    assert np.isnan(values[first]) or np.all(values[first : last + 1] == values[first])


def machine(n_rows: int = 2000, seed: int = 0, step: float = 0.01) -> np.ndarray:
    """Four sensors of a machine warming and cooling (two heat pulses), noise, read to ``step``."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_rows) / n_rows
    rise = np.where(t < 0.5, 1 - np.exp(-t / 0.1), (1 - np.exp(-5)) * np.exp(-(t - 0.5) / 0.15))
    gains = np.array([8.0, 5.0, 3.0, 6.0])
    temps = 22 + rise[:, None] * gains + rng.normal(0, 0.03, (n_rows, 4))
    return np.round(temps / step) * step


def test_a_sensor_stuck_while_the_machine_warms_is_named_with_its_rows():
    temps = machine()
    temps[100:600, 2] = temps[100, 2]
    found = stuck_stretches(temps, ["A", "B", "C", "D"])
    assert [(name, first, last) for name, first, last, _ in found] == [("C", 100, 599)]
    assert found[0][3] > 0.5


def test_a_short_flat_stretch_a_coarse_sensor_and_a_quiet_machine_are_not_named():
    names = ["A", "B", "C", "D"]
    short = machine()
    short[300:450, 2] = short[300, 2]  # 7.5 % of the run
    assert stuck_stretches(short, names) == []
    coarse = machine()
    coarse[:, 2] = 22 + np.round((coarse[:, 2] - 22) / 3.0) * 0.1  # 0.1 K steps, a range of 10 steps
    assert resolution(coarse[:, 2]) == pytest.approx(0.1) and stuck_stretches(coarse, names) == []
    quiet = machine()
    quiet[1500:, :] = quiet[1500]  # the machine at rest: every sensor holds
    quiet[1500:, 0] += np.round(np.random.default_rng(1).normal(0, 0.02, 500), 2)
    assert stuck_stretches(quiet, names) == []


def test_fit_names_the_stuck_sensor_on_loading(tmp_path, capsys):
    temps = machine()
    temps[100:600, 2] = temps[100, 2]
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"])
    frame.insert(0, "time_s", np.arange(len(frame)) * 30.0)
    frame["error_um"] = temps @ np.array([1.0, -0.5, 0.8, 0.3])
    path = tmp_path / "stuck.csv"
    frame.to_csv(path, index=False)
    args = ["fit", "--data", str(path), "--p", "0", "--recalibrate", "none", "--quiet", "--out", str(tmp_path / "o")]
    assert main(args) == 0
    note = next(line for line in capsys.readouterr().out.splitlines() if "unchanged" in line)
    assert "'T3'" in note and "rows 101-600" in note and "4.16 h" in note and "25 % of the run" in note


@pytest.mark.skipif(not SHARED_TEST.exists(), reason="the shared measured data are not present")
def test_the_measured_spindle_test_has_no_stuck_sensor():
    frame = pd.read_csv(SHARED_TEST)
    names = [f"t{k}_C" for k in range(1, 17)]
    assert stuck_stretches(frame[names].to_numpy(float), names) == []
    frame.loc[1000:1999, "t7_C"] = frame.loc[1000, "t7_C"]  # 4.2 h of the test held
    assert [found[:3] for found in stuck_stretches(frame[names].to_numpy(float), names)] == [("t7_C", 1000, 1999)]


def test_a_dead_sensor_and_gaps_are_not_stuck_and_raise_no_warning():
    temps = machine()
    temps[:, 1] = np.nan  # a dead input
    temps[500:900, 3] = np.nan  # a gap
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert stuck_stretches(temps, ["A", "B", "C", "D"]) == []
