"""A lumped thermal-network run: quick, physically shaped test data.

Each temperature sensor and each structural part whose expansion makes up the
thermal error is a first-order thermal capacity heated by the spindle,
``τ·dθ/dt = g·q(t) − θ``, with its own time constant τ and gain g. The sensors
therefore lag the heat input differently, and the error, a weighted sum of
part temperatures (some unsensed), is not a fixed linear function of the
sensors: the mapping changes with the operating condition, which is what
grouped regression exploits. Updates are exact for piecewise-constant heat.

This is a stand-in for the finite-element generator (:mod:`groupfit.fe`) where
a quick run is enough: unit tests, the GA benchmark, examples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from groupfit.errors import InputError

PAPER_SCHEDULE = ((3000.0, 1.0), (1000.0, 0.0), (4000.0, 1.0), (1000.0, 0.0), (21000.0, 1.0))
"""(duration s, relative heat) steps of the paper's cycle, the last held to 30 000 s."""


@dataclass(frozen=True)
class Lag:
    """A first-order thermal capacity: time constant (s), gain (K per unit heat)."""

    tau_s: float
    gain: float


DEFAULT_SENSORS = {
    "T1": Lag(500.0, 9.0),
    "T2": Lag(1400.0, 7.0),
    "T3": Lag(3200.0, 5.0),
    "T4": Lag(7000.0, 3.5),
}
DEFAULT_PARTS = (
    (Lag(350.0, 1.0), 6.0),
    (Lag(2500.0, 1.0), 9.0),
    (Lag(12000.0, 1.0), 14.0),
)
"""(lag, µm per K) of the structural parts whose expansion is the error."""


def heat_series(schedule, period_s: float, n_samples: int, substeps: int) -> np.ndarray:
    """Relative heat at every sub-step of every sampling interval (held after the schedule ends)."""
    dt = period_s / substeps
    times = (np.arange(n_samples * substeps) + 0.5) * dt
    ends = np.cumsum([d for d, _ in schedule])
    levels = np.array([q for _, q in schedule] + [schedule[-1][1]])
    return levels[np.searchsorted(ends, times, side="right")]


def lag_response(lag: Lag, heat: np.ndarray, dt: float) -> np.ndarray:
    """Exact response of a first-order lag to piecewise-constant heat, starting at 0."""
    decay = np.exp(-dt / lag.tau_s)
    theta = np.empty(len(heat))
    state = 0.0
    for i, q in enumerate(heat):
        state = decay * state + (1.0 - decay) * lag.gain * q
        theta[i] = state
    return theta


def simulate_lumped(config: dict) -> pd.DataFrame:
    """Run the lumped model described by a ``kind = "lumped"`` configuration.

    Keys (all optional): ``period_s`` (100), ``n_samples`` (300),
    ``ambient_c`` (20), ``noise_c`` (0.02, sensor noise σ in °C), ``seed`` (0),
    ``schedule`` (list of ``[duration_s, relative_heat]``, default the paper's
    cycle), ``sensors`` (table name → ``[tau_s, gain]``).
    """
    known = {"kind", "period_s", "n_samples", "ambient_c", "noise_c", "seed", "schedule", "sensors", "substeps"}
    unknown = sorted(set(config) - known)
    if unknown:
        raise InputError(f"lumped config: unknown key '{unknown[0]}'; known keys: {', '.join(sorted(known))}")
    period = float(config.get("period_s", 100.0))
    n_samples = int(config.get("n_samples", 300))
    substeps = int(config.get("substeps", 10))
    if period <= 0 or n_samples < 2 or substeps < 1:
        raise InputError("lumped config: period_s must be > 0, n_samples ≥ 2 and substeps ≥ 1")
    schedule = [tuple(map(float, step)) for step in config.get("schedule", PAPER_SCHEDULE)]
    if any(d <= 0 for d, _ in schedule):
        raise InputError("lumped config: every schedule step needs a positive duration")
    sensors = {name: Lag(*map(float, value)) for name, value in config.get("sensors", {}).items()} or DEFAULT_SENSORS
    ambient = float(config.get("ambient_c", 20.0))
    rng = np.random.default_rng(int(config.get("seed", 0)))
    noise = float(config.get("noise_c", 0.02))

    dt = period / substeps
    heat = heat_series(schedule, period, n_samples, substeps)
    sample = slice(substeps - 1, None, substeps)
    table = {"time_s": np.arange(1, n_samples + 1) * period}
    for name, lag in sensors.items():
        table[name] = ambient + lag_response(lag, heat, dt)[sample] + noise * rng.standard_normal(n_samples)
    error = sum(weight * lag_response(lag, heat, dt)[sample] for lag, weight in DEFAULT_PARTS)
    table["error_um"] = error + 0.05 * rng.standard_normal(n_samples)
    table["spindle_on"] = (heat[sample] > 0).astype(int)
    return pd.DataFrame(table)
