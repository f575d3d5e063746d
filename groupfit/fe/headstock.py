"""Transient thermal and quasi-static thermo-elastic model of the headstock.

Heat conduction ``ρc ∂T/∂t = ∇·(λ∇T)`` in the housing with

* bearing heat ``Q_front(n)``, ``Q_rear(n)`` as a uniform flux on the front and
  rear bearing seats (see :func:`groupfit.fe.schedule.bearing_heat_W`);
* extra heat sources as uniform fluxes on the boundary facets of their regions;
* convection ``h (T − T_amb)`` on the outer faces and on the free bore surface;
* a contact conductance ``h_mount (T − T_bed)`` on the mounting face, the bed
  being held at the ambient temperature;
* optionally, an unsensed slow part of the structure (``[unsensed_part]``, see
  :mod:`groupfit.fe.unsensed`) whose first-order lag adds to the error only.

Time integration is backward Euler with a fixed sub-step; the system matrix is
factorised once. The mounting face is clamped; the thermal error is the
displacement of the spindle axis at the nose (the arc-length-weighted mean
displacement of the bore-surface nodes in the front-seat mid-plane) along the
configured direction, relative to the clamped mounting, in µm. It is evaluated
as ``gᵀ(T − T_ref)`` with ``g`` from one adjoint elasticity solve.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import scipy.sparse as sp
from scipy.sparse.linalg import cg, splu
from skfem import Basis, BilinearForm, ElementHex1, ElementVector, FacetBasis, Functional, asm, condense, solve
from skfem.helpers import div
from skfem.models.elasticity import lame_parameters, linear_elasticity
from skfem.models.poisson import laplace, mass, unit_load
from tqdm import tqdm

from groupfit.errors import InputError

from .config import HeadstockScenario, Material, ThermalBoundary
from .geometry import (
    BORE_FREE,
    FRONT_SEAT,
    MOUNT,
    OUTER,
    REAR_SEAT,
    HousingMesh,
    boundary_facets_in_box,
    build_housing_mesh,
)
from .noise import add_noise
from .schedule import bearing_heat_W
from .unsensed import FirstOrderLag

_UNIT = Functional(lambda w: 1.0 + 0.0 * w.x[0])

# 2×2×2 Gauss points: exact for the mass and stiffness of parallelepiped
# hexahedra, and the standard full integration of trilinear ones otherwise.
QUADRATURE_ORDER = 3


def solve_spd(matrix: sp.spmatrix, rhs: np.ndarray, rtol: float = 1e-11) -> np.ndarray:
    """Solve a symmetric positive definite system by Jacobi-preconditioned CG.

    Memory stays linear in the system size, which keeps refined elasticity
    meshes affordable; a sparse LU is the fallback if CG does not converge.
    """
    matrix = matrix.tocsr()
    jacobi = sp.diags(1.0 / matrix.diagonal())
    options = dict(M=jacobi, atol=0.0, maxiter=20 * matrix.shape[0])
    try:
        x, info = cg(matrix, rhs, rtol=rtol, **options)
    except TypeError:  # SciPy < 1.12 names the tolerance ``tol``
        x, info = cg(matrix, rhs, tol=rtol, **options)
    if info != 0:
        x = factorize(matrix).solve(rhs)
    return x


def factorize(matrix: sp.spmatrix):
    """Sparse LU with a fill-reducing ordering suited to symmetric patterns."""
    return splu(matrix.tocsc(), permc_spec="MMD_AT_PLUS_A")


class ThermalModel:
    """Assembled heat-conduction operators of the housing.

    Attributes
    ----------
    capacity
        Lumped ``ρc·M`` (J/K).
    conductance
        Conduction plus all surface exchange terms (W/K).
    ambient_load
        Load per kelvin of ambient (and bed) temperature (W/K).
    bed_load
        The mounting face's part of ``ambient_load``: heat into the bed is
        ``bed_load @ (T − T_amb)``.
    flux_shapes
        For each heated boundary, the load vector of 1 W spread uniformly.
    """

    def __init__(self, housing: HousingMesh, material: Material, boundary: ThermalBoundary):
        self.housing = housing
        self.boundary = boundary
        mesh = housing.mesh
        self.basis = Basis(mesh, ElementHex1(), intorder=QUADRATURE_ORDER)
        self.facet_bases = {
            name: FacetBasis(mesh, self.basis.elem, facets=facets, intorder=QUADRATURE_ORDER)
            for name, facets in mesh.boundaries.items()
        }
        self.exchange = {
            OUTER: boundary.convection,
            BORE_FREE: boundary.bore_convection,
            MOUNT: boundary.mount_conductance,
        }

        # Row-sum lumped capacity: keeps backward Euler free of the spurious
        # undershoot below the initial temperature that consistent mass gives
        # next to a suddenly heated surface.
        consistent = asm(mass, self.basis)
        self.capacity = (
            material.density * material.heat_capacity * sp.diags(np.asarray(consistent.sum(axis=1)).ravel()).tocsr()
        )
        conductance = material.conductivity * asm(laplace, self.basis)
        self.ambient_load = np.zeros(self.basis.N)
        for name, h in self.exchange.items():
            fb = self.facet_bases[name]
            conductance = conductance + h * asm(mass, fb)
            self.ambient_load += h * asm(unit_load, fb)
        self.conductance = conductance.tocsr()
        # h_mount·∫φ_i dA: heat into the bed is bed_load·(T − T_amb)
        self.bed_load = boundary.mount_conductance * asm(unit_load, self.facet_bases[MOUNT])
        self.flux_shapes = {name: self._unit_flux(self.facet_bases[name]) for name in (FRONT_SEAT, REAR_SEAT)}

    def area(self, facet_basis: FacetBasis) -> float:
        return float(asm(_UNIT, facet_basis))

    def _unit_flux(self, facet_basis: FacetBasis) -> np.ndarray:
        return asm(unit_load, facet_basis) / self.area(facet_basis)

    def add_source(self, name: str, box: np.ndarray, config_key: str = "sources") -> FacetBasis:
        """Register a 1 W uniform flux on the boundary facets inside ``box``."""
        facets = boundary_facets_in_box(self.housing.mesh, box)
        if len(facets) == 0:
            raise InputError(
                f"config key '{config_key}': the region of source {name!r} "
                "contains no boundary face of the housing; move the box "
                "onto a face"
            )
        fb = FacetBasis(self.housing.mesh, self.basis.elem, facets=facets, intorder=QUADRATURE_ORDER)
        self.facet_bases[f"src_{name}"] = fb
        self.flux_shapes[f"src_{name}"] = self._unit_flux(fb)
        return fb

    def load(self, heat_W: dict[str, float], ambient_C: float) -> np.ndarray:
        """Right-hand side for the given heat inputs (W per flux shape name)."""
        f = ambient_C * self.ambient_load
        for name, power in heat_W.items():
            if power:
                f = f + power * self.flux_shapes[name]
        return f

    def steady_temperature(self, heat_W: dict[str, float], ambient_C: float) -> np.ndarray:
        return solve_spd(self.conductance, self.load(heat_W, ambient_C))

    def heat_in_W(self, name: str) -> float:
        """Power of a 1 W flux shape integrated back over its surface (check)."""
        return float(np.sum(self.flux_shapes[name]))

    def bed_heat_W(self, temperature: np.ndarray, ambient_C: float) -> float:
        """Heat flowing from the housing through the mounting face into the bed
        (held at ``ambient_C``): ``h_mount ∫ (T − T_amb) dA``."""
        return float(self.bed_load @ temperature - ambient_C * np.sum(self.bed_load))

    def heat_out_W(self, temperature: np.ndarray, ambient_C: float) -> dict[str, float]:
        """Heat leaving through each exchange boundary, integrated from ``T``."""
        out = {}
        for name, h in self.exchange.items():
            fb = self.facet_bases[name]
            flux = Functional(lambda w, h=h: h * (w["T"] - ambient_C))
            out[name] = float(asm(flux, fb, T=fb.interpolate(temperature)))
        return out


class ThermoElasticModel:
    """Linear quasi-static thermo-elasticity on the thermal mesh.

    ``K u = B ΔT``: ``K`` the elastic stiffness, ``B`` maps nodal temperature
    rises to thermal loads ``∫ (3λ+2μ)·α·ΔT·div v``.
    """

    def __init__(self, basis: Basis, material: Material):
        self.scalar_basis = basis
        self.basis = basis.with_element(ElementVector(basis.elem))
        lam, mu = lame_parameters(material.young, material.poisson)
        self.stiffness = asm(linear_elasticity(lam, mu), self.basis).tocsr()
        beta = (3.0 * lam + 2.0 * mu) * material.expansion
        thermal = BilinearForm(lambda T, v, w: beta * T * div(v))
        self.coupling = asm(thermal, basis, self.basis).tocsr()
        self.clamped = self.basis.get_dofs(MOUNT).all()

    def node_dofs(self, nodes: np.ndarray, component: int) -> np.ndarray:
        return self.basis.nodal_dofs[component, nodes]

    def displacement(self, delta_T: np.ndarray, fixed_dofs: np.ndarray | None = None) -> np.ndarray:
        """Direct solve for the displacement field (m)."""
        fixed = self.clamped if fixed_dofs is None else fixed_dofs
        return solve(*condense(self.stiffness, self.coupling @ delta_T, D=fixed), solver=solve_spd)

    def functional_weights(self, nodes: np.ndarray, weights: np.ndarray, direction) -> np.ndarray:
        """Vector ``w`` with ``wᵀu`` = weighted mean displacement along ``direction``."""
        w = np.zeros(self.basis.N)
        for component, d in enumerate(direction):
            w[self.node_dofs(nodes, component)] += d * weights
        return w

    def adjoint_gain(self, weights: np.ndarray) -> np.ndarray:
        """``g`` with ``gᵀΔT = wᵀu`` for the clamped body (one adjoint solve)."""
        z = solve(*condense(self.stiffness, weights, D=self.clamped), solver=solve_spd)
        return self.coupling.T @ z


def nose_error_gain(thermal: ThermalModel, elastic: ThermoElasticModel, direction) -> np.ndarray:
    """Gain ``g`` (µm/K per node) so that the error is ``g @ (T − T_ref)``."""
    housing = thermal.housing
    w = elastic.functional_weights(housing.nose_nodes, housing.nose_weights, direction)
    return 1e6 * elastic.adjoint_gain(w)


def _sensor_matrix(basis: Basis, sensors: dict) -> sp.csr_matrix:
    if not sensors:
        return sp.csr_matrix((0, basis.N))
    points = np.array(list(sensors.values()), dtype=float).T
    try:
        return basis.probes(points).tocsr()
    except ValueError as exc:
        raise InputError(f"config key 'sensors': a sensor point lies outside the meshed housing ({exc})") from None


def _candidate_nodes(housing: HousingMesh, which: str, max_count: int) -> np.ndarray:
    if which == "none":
        return np.zeros(0, dtype=int)
    nodes = housing.surface_nodes if which == "surface" else np.arange(housing.mesh.nvertices)
    if max_count and len(nodes) > max_count:
        pick = np.round(np.linspace(0, len(nodes) - 1, max_count)).astype(int)
        nodes = nodes[np.unique(pick)]
    return nodes


def _heat_inputs(sc: HeadstockScenario, speed_rpm: float, t: float) -> dict[str, float]:
    """Power (W) of every heated boundary at spindle speed ``speed_rpm`` and time ``t``."""
    b = sc.bearings
    heat = {
        FRONT_SEAT: bearing_heat_W(b.front_W, speed_rpm, b.reference_speed_rpm, b.speed_exponent),
        REAR_SEAT: bearing_heat_W(b.rear_W, speed_rpm, b.reference_speed_rpm, b.speed_exponent),
    }
    for src in sc.sources:
        heat[f"src_{src.name}"] = src.power_W * src.schedule.value_at(t)
    return heat


def simulate_headstock(sc: HeadstockScenario, *, progress: bool = True) -> pd.DataFrame:
    """Run the headstock scenario and return the sampled data set.

    The frame's ``attrs["equilibrium_reached"]`` tells whether a hold ended by
    the equilibrium rule (``False`` when it hit ``max_duration_s``).
    """
    housing = build_housing_mesh(sc.geometry, sc.resolution)
    thermal = ThermalModel(housing, sc.material, sc.boundary)
    for index, src in enumerate(sc.sources, start=1):
        thermal.add_source(src.name, np.array(src.region), f"sources[{index}].region_m")
    gain = nose_error_gain(thermal, ThermoElasticModel(thermal.basis, sc.material), sc.error_direction)
    probes = _sensor_matrix(thermal.basis, sc.sensors)
    candidates = _candidate_nodes(housing, sc.candidates, sc.candidate_count)

    period = sc.sampling_period_s
    dt = period / sc.substeps
    capacity_rate = (thermal.capacity / dt).tocsr()
    factor = factorize(capacity_rate + thermal.conductance)

    schedule_end = sc.spindle.total_duration
    fixed_samples = math.ceil(schedule_end / period - 1e-9)
    holding = sc.hold_until_equilibrium_rpm is not None
    max_samples = int(sc.max_duration_s // period + 1e-9) if holding else fixed_samples

    def speed_at(t: float) -> float:
        if holding and t >= schedule_end - 1e-9:
            return sc.hold_until_equilibrium_rpm
        return sc.spindle.value_at(t)

    reference_C = sc.ambient.temperature(0.0)
    temperature = np.full(thermal.basis.N, reference_C)
    rows, errors = [], []
    part = sc.unsensed_part
    lag = FirstOrderLag(part, dt) if part is not None else None

    def record(k: int, t_condition: float):
        error = float(gain @ (temperature - reference_C))
        if lag is not None:
            error += lag.error_um
        errors.append(error)
        speed = speed_at(t_condition)
        rows.append(
            [
                k * period,
                *(probes @ temperature),
                sc.ambient.temperature(k * period),
                errors[-1],
                speed,
                float(speed > 0),
            ]
            + [src.schedule.value_at(t_condition) for src in sc.sources]
            + list(temperature[candidates])
        )

    if sc.prerun is not None:  # warm start: run the spindle before t = 0, unrecorded
        ambient_start = sc.ambient.temperature(0.0)
        n_steps = int(round(sc.prerun.total_duration / dt))
        for s in range(n_steps):
            t0 = s * dt
            heat = _heat_inputs(sc, sc.prerun.value_at(t0), -1.0)
            temperature = factor.solve(capacity_rate @ temperature + thermal.load(heat, ambient_start))
            if lag is not None:
                lag.step(
                    heat[FRONT_SEAT] + heat[REAR_SEAT]
                    if part.heat == "bearings"
                    else thermal.bed_heat_W(temperature, ambient_start)
                )

    record(0, 0.0)
    reached = not holding
    with tqdm(total=max_samples, disable=not progress, unit="sample", desc="headstock") as bar:
        for k in range(1, max_samples + 1):
            for s in range(sc.substeps):
                t0 = (k - 1) * period + s * dt
                heat = _heat_inputs(sc, speed_at(t0), t0)
                ambient_C = sc.ambient.temperature(t0 + 0.5 * dt)
                load = thermal.load(heat, ambient_C)
                temperature = factor.solve(capacity_rate @ temperature + load)
                if lag is not None:
                    lag.step(
                        heat[FRONT_SEAT] + heat[REAR_SEAT]
                        if part.heat == "bearings"
                        else thermal.bed_heat_W(temperature, ambient_C)
                    )
            record(k, (k - 1) * period)
            bar.update(1)
            if holding and k > fixed_samples and sc.equilibrium.reached(np.asarray(errors), fixed_samples, period):
                reached = True
                break
    if not reached:
        warnings.warn(
            f"thermal equilibrium not reached within max_duration_s = "
            f"{sc.max_duration_s:g} s; the data set stops there",
            stacklevel=2,
        )

    columns = (
        ["time_s", *sc.sensors, "T_amb", "error_um", "speed_rpm", "spindle_on"]
        + [f"src_{src.name}_on" for src in sc.sources]
        + [f"node_{n}" for n in candidates]
    )
    frame = pd.DataFrame(rows, columns=columns)
    frame = add_measurement_noise(frame, [*sc.sensors, "T_amb"], sc.noise)
    frame.attrs["equilibrium_reached"] = reached
    return frame


def add_measurement_noise(frame: pd.DataFrame, sensors: list[str], noise) -> pd.DataFrame:
    """The sensor and probe columns with seeded noise and quantisation (:class:`MeasurementNoise`)."""
    if not noise.any:
        return frame
    frame = frame.copy()
    temps, error = add_noise(frame[sensors].to_numpy(dtype=float), frame["error_um"].to_numpy(dtype=float), noise)
    frame[sensors] = temps
    frame["error_um"] = error
    return frame
