"""Seeded measurement noise on simulated readings: the instruments, not the physics."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MeasurementNoise:
    """Seeded measurement noise of a simulated run (``[noise]``); all zero means the exact FE values.

    Temperature sensors: Gaussian noise of ``sensor_sd_K``, then quantisation to
    ``sensor_resolution_K`` (a PT100 and its transmitter: a few 0.01 K, 0.01 K).
    Displacement probe: Gaussian noise of ``probe_sd_um``, then quantisation to
    ``probe_resolution_um``. The draws come from
    ``numpy.random.default_rng(seed)``, sensors first (row by row), then the
    probe, so a config always gives the same numbers.
    """

    sensor_sd_K: float = 0.0
    sensor_resolution_K: float = 0.0
    probe_sd_um: float = 0.0
    probe_resolution_um: float = 0.0
    seed: int = 0

    @property
    def any(self) -> bool:
        return bool(self.sensor_sd_K or self.sensor_resolution_K or self.probe_sd_um or self.probe_resolution_um)


def read_noise(table) -> MeasurementNoise:
    """The instruments' keys of a ``[noise]`` table (a :class:`groupfit.tomlconfig.Table`); the caller finishes it."""
    seed = table.integer("seed", 0, minimum=0)
    return MeasurementNoise(
        sensor_sd_K=table.number("sensor_sd_K", 0.0, nonnegative=True),
        sensor_resolution_K=table.number("sensor_resolution_K", 0.0, nonnegative=True),
        probe_sd_um=table.number("probe_sd_um", 0.0, nonnegative=True),
        probe_resolution_um=table.number("probe_resolution_um", 0.0, nonnegative=True),
        seed=seed,
    )


def add_noise(temps: np.ndarray, error: np.ndarray, noise) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian noise, then quantisation to the instruments' resolution; new arrays.

    ``noise``: a :class:`MeasurementNoise`.
    """
    rng = np.random.default_rng(noise.seed)
    temps = temps + rng.normal(0.0, noise.sensor_sd_K, temps.shape) if noise.sensor_sd_K else temps.copy()
    error = error + rng.normal(0.0, noise.probe_sd_um, error.shape) if noise.probe_sd_um else error.copy()
    if noise.sensor_resolution_K:
        temps = np.round(temps / noise.sensor_resolution_K) * noise.sensor_resolution_K
    if noise.probe_resolution_um:
        error = np.round(error / noise.probe_resolution_um) * noise.probe_resolution_um
    return temps, error
