"""The diagnosis tests' scenarios: small synthetic machines with a known missing effect, and their base models.

``lumped`` is the lumped thermal network on the paper's duty cycle with a
daily ambient and an HVAC step; ``sensor_error`` gives it an error its four
sensors explain completely, ``with_ambient_effect`` adds a lag of the air
no sensor reads. ``spindle_run`` is a spindle on hourly speed steps with a
heat-law lag no sensor sees. ``global_model`` fits the base model a
diagnosis starts from (p = 0) in the process; ``fit_model`` writes one with
``groupfit fit``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from groupfit.cli import main
from groupfit.data import Run
from groupfit.features import lowpass
from groupfit.models.grouped import GroupedRegressor
from groupfit.synthetic import simulate_lumped

TEMPS = ["T1", "T2", "T3", "T4"]
"""The lumped network's sensors."""
SPINDLE_PERIOD_S = 30.0
SPINDLE_SENSORS = [f"T{k}" for k in range(1, 9)]
"""The spindle run's sensors: T1 and seven near copies of it."""


def lumped(seed=0, n_samples=400, schedule=None, ambient_phase_h=0.0) -> pd.DataFrame:
    config = {"seed": seed, "n_samples": n_samples}
    if schedule is not None:
        config["schedule"] = schedule
    frame = simulate_lumped(config)
    hours = frame["time_s"].to_numpy() / 3600.0
    frame["T_amb"] = 20.0 + 2.0 * np.sin(2 * np.pi * (hours - ambient_phase_h) / 24.0) + 1.5 * (hours > 6.0)
    return frame


def sensor_error(frame: pd.DataFrame, seed=2) -> pd.DataFrame:
    """An error the sensors explain completely, plus noise (the lumped network's own has an unsensed part)."""
    frame = frame.copy()
    rng = np.random.default_rng(seed)
    frame["error_um"] = frame[TEMPS].to_numpy() @ [0.8, 0.5, 1.1, 2.0] - 80.0 + rng.normal(scale=0.05, size=len(frame))
    return frame


def with_ambient_effect(frame: pd.DataFrame, gain=1.2, tau=3600.0) -> pd.DataFrame:
    frame = sensor_error(frame)
    frame["error_um"] = frame["error_um"] + gain * lowpass(frame["T_amb"].to_numpy() - 20.0, tau, 100.0)
    return frame


def spindle_run(seed, hours=16.0) -> pd.DataFrame:
    """Speed steps of an hour; T1 follows the bearings and the air, T2…T8 are near copies of it; the error lags more.

    The error is 3 µm/K of T1 plus a part no sensor sees: the heat law (n/1000)^(5/3) low-passed with τ = 2 h.
    """
    rng = np.random.default_rng(seed)
    n = int(hours * 3600 / SPINDLE_PERIOD_S)
    speed = np.repeat(rng.choice([0.0, 1000.0, 2000.0, 3000.0, 4000.0, 5000.0, 6000.0], size=int(hours)), 120)[:n]
    heat = (speed / 1000.0) ** (5 / 3)
    frame = pd.DataFrame({"time_s": np.arange(n) * SPINDLE_PERIOD_S, "speed_rpm": speed})
    ambient = 1.5 * np.sin(2 * np.pi * (frame["time_s"] / 86400.0 + rng.uniform()))  # the speed does not say it
    bearings = 0.4 * lowpass(heat, 1200.0, SPINDLE_PERIOD_S, before=0.0)
    frame["T1"] = 20.0 + ambient + bearings + rng.normal(scale=0.02, size=n)
    for k in range(2, 9):  # copies that drift apart a little: a base model on all of them over-fits
        walk = np.cumsum(rng.normal(scale=0.004, size=n))
        frame[f"T{k}"] = frame["T1"] + walk + rng.normal(scale=0.02, size=n)
    unsensed = 0.8 * lowpass(heat, 7200.0, SPINDLE_PERIOD_S, before=0.0)
    frame["error_um"] = 3.0 * (frame["T1"] - 20.0) + unsensed + rng.normal(scale=0.05, size=n)
    return frame


def global_model(run: Run) -> dict:
    """The model file (as its JSON object) of a global model (p = 0) on ``run``'s inputs."""
    return GroupedRegressor(p=0).fit(run.temps, run.error).to_model_file(run).to_dict()


def fit_model(tmp_path, frame: pd.DataFrame, name: str, p=0):
    """``groupfit fit`` on ``frame`` (written as ``name.csv``) with the lumped sensors, on absolute readings;
    the data file and the model file."""
    path = tmp_path / f"{name}.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / f"{name}-model"
    args = ["fit", "--data", str(path), "--temps", ",".join(TEMPS), "--p", str(p), "--search", "exact"]
    args += ["--reference", "none"]  # the lumped machine's error is defined on absolute readings
    assert main([*args, "--out", str(out), "--quiet"]) == 0
    return path, out / "model.json"
