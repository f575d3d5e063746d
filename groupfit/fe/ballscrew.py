"""Ball screw: transient heat conduction along a steel screw (scikit-fem).

The screw is a fin of radius R0 = d/2: for the temperature rise θ above
ambient,

``ρc ∂θ/∂t = k ∂²θ/∂x² − (2h/R0)·θ + q(x, t)/A``,   ``A = π R0²``,

with convection h on the lateral surface (the sink ``2h/R0·θ``), h also on the
free end face x = L, and the heat input q either

* ``"fixed"``: a fixed source of ``power_W × into_screw`` watts at ``x_m``
  (x = 0, the end face, is the set-up of seed 003: a heater at one end), on
  while its schedule is 1; or
* ``"nut"``: a nut of length ``nut_length_m`` travelling along a programme of
  ``[target_m, speed_m_s, dwell_s]`` moves; its friction heat ``power_W`` at
  ``reference_speed_m_s`` scales with the speed (zero while it dwells) and is
  spread uniformly over the nut; the support bearing at x = 0 adds
  ``bearing_power_W`` at the same reference speed.

The thermal error at a point x is its axial displacement: with the screw fixed
at x = 0 and free at L (``"fixed-free"``), ``u(x) = a ∫₀ˣ θ dξ``; held at both
ends (``"fixed-fixed"``, rigid supports, pre-tension relieved by the heat),
``u(x) = a [∫₀ˣ θ dξ − (x/L) ∫₀ᴸ θ dξ]``.

Linear P1 elements on a line (``MeshLine``), operators assembled with
scikit-fem forms, backward Euler with ``substeps`` steps per sample.
:func:`simulate_axisymmetric` solves the same screw as a 2-D axisymmetric body
(forms weighted by 2πr) to check that the fin reduction holds; see
``docs/ballscrew.md``.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.sparse.linalg import splu
from skfem import Basis, BilinearForm, ElementLineP1, FacetBasis, LinearForm, MeshLine, asm
from tqdm import tqdm

from groupfit.errors import InputError

from .ballscrew_config import (  # noqa: F401 - the scenario's names, re-exported with the solver
    BEARINGS,
    PAPER_SENSORS,
    RESERVED,
    SOURCES,
    BallScrewScenario,
    Programme,
    Screw,
    Source,
    parse_ballscrew,
)
from .noise import add_noise

# ---------------------------------------------------------------- operators


@BilinearForm
def _stiffness(u, v, w):
    return u.grad[0] * v.grad[0]


@BilinearForm
def _mass(u, v, w):
    return u * v


class ScrewModel:
    """Assembled fin operators of one screw: capacity, conductance and probes.

    Parameters
    ----------
    screw : Screw
    elements : int
        P1 elements along the screw (uniform).
    """

    def __init__(self, screw: Screw, elements: int):
        self.screw = screw
        self.nodes = np.linspace(0.0, screw.length, elements + 1)
        mesh = MeshLine(self.nodes)
        element = ElementLineP1()
        self.basis = Basis(mesh, element)
        free_end = FacetBasis(mesh, element, facets=mesh.facets_satisfying(lambda x: x[0] > screw.length * (1 - 1e-9)))
        perimeter = 2.0 * math.pi * screw.radius
        m = asm(_mass, self.basis)
        self.capacity = (screw.density * screw.heat_capacity * screw.area) * m
        self.conductance = (
            screw.conductivity * screw.area * asm(_stiffness, self.basis)
            + screw.convection * perimeter * m
            + screw.convection * screw.area * asm(_mass, free_end)
        )

    def point_load(self, x: float) -> np.ndarray:
        """Load vector of 1 W put in at ``x``."""
        return self.basis.point_source(np.array([x]))

    def band_load(self, centre: float, length: float) -> np.ndarray:
        """Load vector of 1 W spread uniformly over ``[centre ± length/2]`` (clipped to the screw)."""
        lo, hi = max(0.0, centre - length / 2), min(self.screw.length, centre + length / 2)

        @LinearForm
        def band(v, w):
            x = w.x[0]
            return v * ((x >= lo) & (x <= hi))

        load = asm(band, self.basis, intorder=8)
        total = load.sum()
        return load / total if total > 0 else self.point_load(min(max(centre, 0.0), self.screw.length))

    def probes(self, x) -> np.ndarray:
        """Interpolation matrix: temperatures at the positions ``x`` from the nodal values."""
        return self.basis.probes(np.atleast_1d(np.asarray(x, dtype=float))[None, :]).toarray()

    def displacement_weights(self, x) -> np.ndarray:
        """Rows g with ``u(x) = g·θ`` in µm: the thermal error at each position ``x``.

        Exact for the P1 field (trapezoid on whole elements, the linear field
        integrated exactly on the last, partial one).
        """
        x = np.atleast_1d(np.asarray(x, dtype=float))
        nodes, n = self.nodes, len(self.nodes)
        weights = np.zeros((len(x), n))
        for row, xp in enumerate(x):
            weights[row] = _integral_weights(nodes, xp)
        if self.screw.bearings == "fixed-fixed":
            whole = _integral_weights(nodes, self.screw.length)
            weights -= (x / self.screw.length)[:, None] * whole[None, :]
        return 1e6 * self.screw.expansion * weights


def _integral_weights(nodes: np.ndarray, x: float) -> np.ndarray:
    """Weights w with ``∫₀ˣ θ dξ = w·θ`` for a piecewise-linear θ on ``nodes``."""
    w = np.zeros(len(nodes))
    k = int(np.searchsorted(nodes, x, side="right")) - 1
    k = min(max(k, 0), len(nodes) - 2)
    h = np.diff(nodes[: k + 1])
    w[:k] += h / 2
    w[1 : k + 1] += h / 2
    s = x - nodes[k]
    e = nodes[k + 1] - nodes[k]
    if s > 0:
        # θ on the partial element: θk·(1 − ξ/e) + θk+1·ξ/e, ξ from 0 to s
        w[k] += s - s * s / (2 * e)
        w[k + 1] += s * s / (2 * e)
    return w


# ------------------------------------------------------------------ solver


def heat_inputs(sc: BallScrewScenario, model: ScrewModel, times: np.ndarray, dt: float):
    """Per time step ending at ``times[i]``: the mean load vector (W) over the step,
    the source power column and, for a nut, its position and speed."""
    src = sc.source
    if src.kind == "fixed":
        unit = model.point_load(src.x) * (src.power_W * src.into_screw)
        on = np.array([src.schedule.value_at(t - dt) for t in times])
        return (lambda i: on[i] * unit), on * src.power_W, None, None
    # nut: average the band load over 4 instants inside each step
    length = sc.screw.length
    grid = np.linspace(0.0, length, int(round(length / 0.001)) + 1)
    table = np.array([model.band_load(c, src.nut_length) for c in grid])
    bearing = model.point_load(0.0)
    offsets = (np.arange(4) + 0.5) / 4 * dt
    position, speed = src.programme.state((times[:, None] - dt) + offsets[None, :])

    def load(i):
        total = np.zeros(model.basis.N)
        for x, v in zip(position[i], speed[i]):
            scale = v / src.reference_speed
            if scale > 0:
                j = min(int(np.searchsorted(grid, x)), len(grid) - 1)
                j0 = max(j - 1, 0)
                frac = 0.0 if j == j0 else (x - grid[j0]) / (grid[j] - grid[j0])
                band = (1 - frac) * table[j0] + frac * table[j]
                total += scale * (src.power_W * band + src.bearing_power_W * bearing)
        return total / len(offsets)

    mean_speed = speed.mean(axis=1)
    power = (src.power_W + src.bearing_power_W) * mean_speed / src.reference_speed
    return load, power, position[:, -1], mean_speed


def solve_field(sc: BallScrewScenario, *, progress: bool = False):
    """Integrate the scenario; return ``(model, times, θ at each sample, power, nut_x, speed)``.

    θ has shape (samples, nodes), the rise above ambient in K.
    """
    model = ScrewModel(sc.screw, sc.elements)
    dt = sc.sampling_period_s / sc.substeps
    n_samples = int(round(sc.duration_s / sc.sampling_period_s))
    step_times = dt * np.arange(1, n_samples * sc.substeps + 1)
    load, power, nut_x, speed = heat_inputs(sc, model, step_times, dt)
    capacity_rate = (model.capacity / dt).tocsr()
    factor = splu((capacity_rate + model.conductance).tocsc())
    theta = np.zeros(model.basis.N)
    field_ = np.zeros((n_samples + 1, model.basis.N))
    for k in tqdm(range(1, n_samples + 1), disable=not progress, unit="sample", desc="ball screw"):
        for s in range(sc.substeps):
            i = (k - 1) * sc.substeps + s
            theta = factor.solve(capacity_rate @ theta + load(i))
        field_[k] = theta
    times = sc.sampling_period_s * np.arange(n_samples + 1)
    at_samples = np.concatenate([[0], np.arange(sc.substeps - 1, len(step_times), sc.substeps)])
    power_col = np.asarray(power)[at_samples]
    nut = None if nut_x is None else np.concatenate([[sc.source.programme.start], nut_x[at_samples[1:]]])
    spd = None if speed is None else np.asarray(speed)[at_samples]
    return model, times, field_, power_col, nut, spd


def simulate_ballscrew(sc: BallScrewScenario, *, progress: bool = True) -> pd.DataFrame:
    """Run the scenario; columns ``time_s``, the sensors (°C), ``error_um``,
    ``probe_x_m`` (a fixed source: the probe's distance from it; a nut: the
    nut's position), ``power_W``, for a nut ``nut_x_m`` and ``screw_rpm``, and
    the exact (noise-free) displacement ``u<mm>mm_um`` at every position of
    ``[probe] displacements_m`` (``u300mm_um`` at the free end of a 0.3 m screw
    is its elongation)."""
    model, times, theta, power, nut_x, speed = solve_field(sc, progress=progress)
    names = list(sc.sensors)
    temps = sc.ambient_C + theta @ model.probes([sc.sensors[n] for n in names]).T
    if sc.probe == "nut":
        probe_x = nut_x
        error = np.array([model.displacement_weights(x)[0] @ th for x, th in zip(probe_x, theta)])
    else:  # the probe's distance from the source, the coordinate of the sensors' names and of the screw law
        probe_x = np.full(len(times), float(sc.probe) - sc.source.x)
        error = theta @ model.displacement_weights(sc.probe)[0]
    temps, error = add_noise(temps, error, sc.noise)
    columns = {"time_s": times}
    columns.update({n: temps[:, j] for j, n in enumerate(names)})
    columns.update({"error_um": error, "probe_x_m": probe_x, "power_W": power})
    if nut_x is not None:
        columns.update({"nut_x_m": nut_x, "screw_rpm": 60.0 * speed / sc.screw.lead})
    if sc.displacements:
        exact = theta @ model.displacement_weights(sc.displacements).T
        columns.update({f"u{1000 * x:g}mm_um": exact[:, j] for j, x in enumerate(sc.displacements)})
    return pd.DataFrame(columns)


def steady_rise_at_source(screw: Screw, power_in_W: float) -> float:
    """Closed-form steady rise (K) at x = 0 of the fin of length L heated at its end
    by ``power_in_W``, with convection on its surface and free end face."""
    lam = screw.fin_parameter
    k, area, h, length = screw.conductivity, screw.area, screw.convection, screw.length
    # θ = A cosh(λ(L−x)) + B sinh(λ(L−x)); −kθ'(L) = hθ(L) → B = A·h/(kλ); −kAθ'(0) = P
    beta = h / (k * lam)
    a = power_in_W / (k * area * lam * (math.sinh(lam * length) + beta * math.cosh(lam * length)))
    return a * (math.cosh(lam * length) + beta * math.sinh(lam * length))


# ------------------------------------------------------ axisymmetric check


def simulate_axisymmetric(
    sc: BallScrewScenario, *, axial: int = 150, radial: int = 6, sensor_radius: float | None = None
) -> dict:
    """The fixed-source screw as a 2-D axisymmetric body (x, r), for verification.

    Heat conduction ``ρc ∂θ/∂t = ∇·(k∇θ)`` on the rectangle ``[0, L] × [0, R0]``
    with every integrand weighted by 2πr; convection h on r = R0 and on the
    free end x = L, the source's power as a uniform flux on the end face
    x = 0 (a fixed source at x = 0 only). Same time step as the fin.

    Returns
    -------
    dict
        ``time_s``, ``temps`` (°C at the sensors, on the surface r = R0 unless
        ``sensor_radius``), ``error_um`` (displacement at the probe from the
        section-mean temperature), ``mean_rise`` at the sensors.
    """
    from skfem import ElementQuad1, MeshQuad

    screw, src = sc.screw, sc.source
    if src.kind != "fixed" or src.x != 0.0 or sc.probe == "nut":
        raise InputError("the axisymmetric check covers a fixed source at x = 0 and a fixed probe")
    R, L = screw.radius, screw.length
    mesh = MeshQuad.init_tensor(np.linspace(0.0, L, axial + 1), np.linspace(0.0, R, radial + 1))
    element = ElementQuad1()
    basis = Basis(mesh, element, intorder=3)
    surface = FacetBasis(
        mesh, element, facets=mesh.facets_satisfying(lambda x: (x[1] > R * (1 - 1e-9)) | (x[0] > L * (1 - 1e-9)))
    )
    end = FacetBasis(mesh, element, facets=mesh.facets_satisfying(lambda x: x[0] < 1e-12 * L))

    @BilinearForm
    def conduction(u, v, w):
        return 2 * math.pi * w.x[1] * (u.grad[0] * v.grad[0] + u.grad[1] * v.grad[1])

    @BilinearForm
    def weighted_mass(u, v, w):
        return 2 * math.pi * w.x[1] * u * v

    @LinearForm
    def end_flux(v, w):
        return 2 * math.pi * w.x[1] * v / (math.pi * R * R)

    capacity = screw.density * screw.heat_capacity * asm(weighted_mass, basis)
    conductance = screw.conductivity * asm(conduction, basis) + screw.convection * asm(weighted_mass, surface)
    unit = asm(end_flux, end)
    power = src.power_W * src.into_screw

    dt = sc.sampling_period_s / sc.substeps
    n_samples = int(round(sc.duration_s / sc.sampling_period_s))
    rate = (capacity / dt).tocsr()
    factor = splu((rate + conductance).tocsc())
    names = list(sc.sensors)
    xs = np.array([sc.sensors[n] for n in names])
    r_s = R if sensor_radius is None else sensor_radius
    surface_probe = basis.probes(np.vstack([xs, np.full_like(xs, r_s)]))
    # section mean of θ along x on a fine grid, then the fin's elongation integral
    x_grid = np.linspace(0.0, L, 4 * axial + 1)
    r_nodes, r_weights = np.polynomial.legendre.leggauss(6)
    r_pts = (r_nodes + 1) / 2 * R
    r_w = (r_weights / 2 * R) * 2 * r_pts / (R * R)  # ∫ θ 2r dr / R²
    pts = np.vstack([np.repeat(x_grid, len(r_pts)), np.tile(r_pts, len(x_grid))])
    section = basis.probes(pts)
    fin = ScrewModel(screw, 4 * axial)  # nodes coincide with x_grid
    g = fin.displacement_weights(float(sc.probe))[0]
    theta = np.zeros(basis.N)
    temps, error, mean_rise = [np.zeros(len(names))], [0.0], [np.zeros(len(names))]
    mean_probe = fin.probes(xs)
    for k in range(1, n_samples + 1):
        for s in range(sc.substeps):
            t = ((k - 1) * sc.substeps + s) * dt
            theta = factor.solve(rate @ theta + src.schedule.value_at(t) * power * unit)
        temps.append(surface_probe @ theta)
        mean = (section @ theta).reshape(len(x_grid), len(r_pts)) @ r_w
        error.append(g @ mean)
        mean_rise.append(mean_probe @ mean)
    return {
        "time_s": sc.sampling_period_s * np.arange(n_samples + 1),
        "temps": sc.ambient_C + np.array(temps),
        "error_um": np.array(error),
        "mean_rise": np.array(mean_rise),
        "names": names,
    }
