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

import numpy as np
import pandas as pd

from groupfit.column_values import ERROR_LIMIT_UM, TEMP_RANGE_C
from groupfit.fe.tables import fail
from groupfit.synthetic_config import Lag, LumpedScenario, parse_lumped

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

    Parameters
    ----------
    config : dict
        The scenario; every key is optional: ``period_s`` (100), ``n_samples``
        (300), ``substeps`` (10), ``ambient_c`` (20), ``noise_c`` (0.02,
        sensor noise σ in °C), ``seed`` (0), ``schedule`` (list of
        ``[duration_s, relative_heat]``, default the paper's cycle),
        ``sensors`` (table name → ``[tau_s, gain]``). The bounds are
        :func:`groupfit.synthetic_config.parse_lumped`'s.

    Returns
    -------
    pandas.DataFrame
        ``time_s`` (from ``period_s``), the sensors (°C), ``error_um`` and ``spindle_on``.

    Raises
    ------
    InputError
        On an unknown key, a wrong type or a value the model cannot run.
    """
    scenario = parse_lumped(config)
    _refuse_implausible_levels(scenario)
    n_samples, substeps = scenario.n_samples, scenario.substeps
    rng = np.random.default_rng(scenario.seed)
    dt = scenario.period_s / substeps
    heat = heat_series(scenario.schedule, scenario.period_s, n_samples, substeps)
    sample = slice(substeps - 1, None, substeps)
    table = {"time_s": np.arange(1, n_samples + 1) * scenario.period_s}
    for name, lag in scenario.sensors.items():
        noise = scenario.noise_c * rng.standard_normal(n_samples)
        table[name] = scenario.ambient_c + lag_response(lag, heat, dt)[sample] + noise
    error = sum(weight * lag_response(lag, heat, dt)[sample] for lag, weight in DEFAULT_PARTS)
    table["error_um"] = error + 0.05 * rng.standard_normal(n_samples)
    table["spindle_on"] = (heat[sample] > 0).astype(int)
    _refuse_implausible_noise(table, scenario)
    return pd.DataFrame(table)


def _refuse_implausible_levels(scenario: LumpedScenario) -> None:
    """Refuse a sensor or an error whose steady level under the schedule's peak heat groupfit would not read back.

    A lag starting at 0 never passes its steady level ``gain × heat``, so the
    peak heat bounds every sample before any is computed.
    """
    peak_heat = max(heat for _, heat in scenario.schedule)
    high = TEMP_RANGE_C[1]
    for name, lag in scenario.sensors.items():
        peak = scenario.ambient_c + lag.gain * peak_heat
        if peak > high:
            raise fail(
                f"sensors.{name}",
                f"gain {lag.gain!r} × the schedule's peak heat {peak_heat!r} over ambient_c {scenario.ambient_c!r} "
                f"reaches {peak:g} °C, above the plausible {high:g} °C; lower the gain or the heat",
            )
    peak_error = sum(weight for _, weight in DEFAULT_PARTS) * peak_heat
    if peak_error > ERROR_LIMIT_UM:
        raise fail(
            "schedule",
            f"relative heat {peak_heat!r} drives the error to {peak_error:g} µm, beyond the plausible "
            f"{ERROR_LIMIT_UM:g} µm; keep the heat of the order of 1",
        )


def _refuse_implausible_noise(table: dict[str, np.ndarray], scenario: LumpedScenario) -> None:
    """Refuse a reading the noise took outside the plausible temperatures (the levels are checked before)."""
    low, high = TEMP_RANGE_C
    for name in scenario.sensors:
        outside = np.flatnonzero((table[name] < low) | (table[name] > high))
        if outside.size:
            raise fail(
                "noise_c",
                f"noise of {scenario.noise_c!r} °C takes {name} to {table[name][outside[0]]:g} °C, outside the "
                f"plausible {low:g}…{high:g} °C; lower noise_c or move ambient_c away from that bound",
            )
