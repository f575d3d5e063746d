"""Seeded measurement noise on simulated readings: the instruments, not the physics."""

from __future__ import annotations

import numpy as np


def add_noise(temps: np.ndarray, error: np.ndarray, noise) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian noise, then quantisation to the instruments' resolution; new arrays.

    ``noise`` has ``seed``, ``sensor_sd_K``, ``sensor_resolution_K``,
    ``probe_sd_um`` and ``probe_resolution_um``. The draws come from
    ``numpy.random.default_rng(seed)``, the sensors first (row by row), then
    the probe, so a config always gives the same numbers.
    """
    rng = np.random.default_rng(noise.seed)
    temps = temps + rng.normal(0.0, noise.sensor_sd_K, temps.shape) if noise.sensor_sd_K else temps.copy()
    error = error + rng.normal(0.0, noise.probe_sd_um, error.shape) if noise.probe_sd_um else error.copy()
    if noise.sensor_resolution_K:
        temps = np.round(temps / noise.sensor_resolution_K) * noise.sensor_resolution_K
    if noise.probe_resolution_um:
        error = np.round(error / noise.probe_resolution_um) * noise.probe_resolution_um
    return temps, error
