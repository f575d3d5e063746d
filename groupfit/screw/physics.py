"""The formulas of the analytic ball-screw model of seed 003 (the estimator is :mod:`groupfit.screw.model`).

Temperature rise at a distance x from the heat source (eq. 7 of the paper)::

    Γ(x, t) = (C1·e^(−λx) + C2·e^(λx)) · [1 − erf((x + x0) / (2·√(α′(τ0)·t)))],
    λ = √(2h / (k·R0)),   α′(τ0) = a0 + a1·τ0,

the first factor the steady profile of a fin with convection h (eq. 5), the
second the erf solution of the heat equation without convection behind a
source whose temperature is held (eq. 3), with the diffusivity replaced by a
coefficient α′ that follows a reference rise τ0 measured at the source
(``alpha_law="line"``, the paper's law), or is read from the α′(t) table
identified on the first source (``alpha_law="table"``, the default).
``x0`` is the distance from the effective source to the sensor at x = 0 (the
*reading* of docs/ballscrew.md; x0 = 0 is the paper's formula as printed).
Thermal error of a screw fixed at x = 0 (eq. 9)::

    E(x, t) = ∫₀ˣ a_m·Γ(ξ, t) dξ.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import erfc

ALPHA_FLOOR = 1e-9
"""Smallest α′ (m²/s) the model uses: the linear law may cross zero for small τ0."""

ALPHA_LAWS = ("table", "line")
"""How α′ is predicted: the identified α′(t) table, or the paper's straight line in τ0."""

_GAUSS = np.polynomial.legendre.leggauss(16)
_PANELS = 16


def fin_parameter(h: float, conductivity: float, radius: float) -> float:
    """λ = √(2h/(k·R0)) (1/m)."""
    return math.sqrt(2.0 * h / (conductivity * radius))


def convection_from_fin_parameter(lam: float, conductivity: float, radius: float) -> float:
    """h = λ²·k·R0/2 (W/(m²·K)), the inverse of :func:`fin_parameter`."""
    return lam * lam * conductivity * radius / 2.0


def steady_profile(x, c1: float, c2: float, lam: float) -> np.ndarray:
    """Steady rise C1·e^(−λx) + C2·e^(λx) (eq. 5)."""
    x = np.asarray(x, dtype=float)
    return c1 * np.exp(-lam * x) + c2 * np.exp(lam * x)


def transient_factor(x, t, alpha, x0: float = 0.0) -> np.ndarray:
    """1 − erf((x + x0)/(2√(α t))), broadcast over x, t and α; 0 at t ≤ 0."""
    x, t, alpha = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, t, alpha)))
    out = np.zeros(x.shape)
    live = t > 0
    out[live] = erfc((x[live] + x0) / (2.0 * np.sqrt(np.maximum(alpha[live], ALPHA_FLOOR) * t[live])))
    return out


def temperature_rise(x, t, c1: float, c2: float, lam: float, alpha, x0: float = 0.0) -> np.ndarray:
    """Γ(x, t) of eq. 7, broadcast over ``x``, ``t`` and ``alpha`` (K)."""
    return steady_profile(x, c1, c2, lam) * transient_factor(x, t, alpha, x0)


def quadrature() -> tuple[np.ndarray, np.ndarray]:
    """The composite Gauss–Legendre nodes ``u`` and weights ``w`` on [0, 1] of :func:`thermal_error`."""
    nodes, weights = _GAUSS
    edges = np.linspace(0.0, 1.0, _PANELS + 1)
    u = ((edges[:-1, None] + edges[1:, None]) / 2 + (nodes[None, :] / 2) * np.diff(edges)[:, None]).ravel()
    w = ((weights[None, :] / 2) * np.diff(edges)[:, None]).ravel()
    return u, w


def thermal_error(x, t, c1: float, c2: float, lam: float, alpha, expansion: float, x0: float = 0.0) -> np.ndarray:
    """E(x, t) = ∫₀ˣ a_m·Γ(ξ, t) dξ in µm (eq. 9), one value per sample.

    ``x``, ``t`` and ``alpha`` are per-sample arrays (or scalars) of one
    shape; the integral is composite Gauss–Legendre (16 panels of 16 points).
    """
    x, t, alpha = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, t, alpha)))
    u, w = quadrature()
    flat_x, flat_t, flat_a = x.ravel(), t.ravel(), alpha.ravel()
    xi = flat_x[:, None] * u[None, :]
    gamma = temperature_rise(xi, flat_t[:, None], c1, c2, lam, flat_a[:, None], x0)
    return (1e6 * expansion * flat_x * (gamma @ w)).reshape(x.shape)
