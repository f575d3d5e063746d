"""1-D spindle rod (docs/methods.md §2 check case), finite elements on a line.

``ρc ∂θ/∂t = λ ∂²θ/∂x² − (2h/R)·θ`` for the temperature rise θ above ambient;
the lateral convection of a rod of radius R becomes the volumetric sink
``2h/R·θ``; heat flux ``q(t)`` enters at x = 0, the far end x = L is insulated.
The thermal error is the elongation ``α∫θ dx`` (µm).

Integrating the equation over the rod gives ``d/dt ∫θ = q/(ρc) − b∫θ`` with
``b = 2h/(ρcR)``, so the elongation sampled every Δτ follows the AR(1) law
``E(k) = C1·E(k−1) + C2(q_k)`` with ``C1 = e^{−bΔτ}`` and
``C2(q) = q·α/(ρcb)·(1 − e^{−bΔτ})`` exactly; the Galerkin discretisation keeps
this property (its stiffness rows sum to zero), up to the time-stepping error of
backward Euler with ``substeps`` steps per sample.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.sparse.linalg import splu
from skfem import Basis, ElementLineP1, ElementLineP2, MeshLine, asm
from skfem.models.poisson import laplace, mass, unit_load
from tqdm import tqdm

from .config import RodScenario


def rod_ar1_coefficients(sc: RodScenario, flux_W_m2: float) -> tuple[float, float]:
    """Closed-form AR(1) coefficients ``(C1, C2 in µm)`` of the rod scenario."""
    b = 2.0 * sc.convection / (sc.density * sc.heat_capacity * sc.radius)
    decay = np.exp(-b * sc.sampling_period_s)
    c2 = flux_W_m2 * sc.expansion / (sc.density * sc.heat_capacity * b) * (1.0 - decay)
    return float(decay), float(1e6 * c2)


class RodModel:
    """Assembled operators of the rod."""

    def __init__(self, sc: RodScenario):
        mesh = MeshLine(np.linspace(0.0, sc.length, sc.elements + 1))
        element = ElementLineP2() if sc.order == 2 else ElementLineP1()
        self.basis = Basis(mesh, element)
        m = asm(mass, self.basis)
        self.capacity = sc.density * sc.heat_capacity * m
        self.conductance = sc.conductivity * asm(laplace, self.basis) + 2.0 * sc.convection / sc.radius * m
        self.inflow = self.basis.point_source(np.array([0.0]))
        self.elongation_um = 1e6 * sc.expansion * asm(unit_load, self.basis)


def simulate_rod(sc: RodScenario, *, progress: bool = True) -> pd.DataFrame:
    """Run the rod scenario: columns ``time_s``, ``q_W_m2``, ``error_um``."""
    model = RodModel(sc)
    dt = sc.sampling_period_s / sc.substeps
    capacity_rate = (model.capacity / dt).tocsr()
    factor = splu((capacity_rate + model.conductance).tocsc(), permc_spec="MMD_AT_PLUS_A")
    n_samples = int(round(sc.flux.total_duration / sc.sampling_period_s))

    theta = np.zeros(model.basis.N)
    times = np.arange(n_samples + 1) * sc.sampling_period_s
    flux = np.empty(n_samples + 1)
    error = np.empty(n_samples + 1)
    flux[0], error[0] = sc.flux.value_at(0.0), 0.0
    for k in tqdm(range(1, n_samples + 1), disable=not progress, unit="sample", desc="rod"):
        q = sc.flux.value_at(times[k - 1])
        for _ in range(sc.substeps):
            theta = factor.solve(capacity_rate @ theta + q * model.inflow)
        flux[k], error[k] = q, model.elongation_um @ theta
    return pd.DataFrame({"time_s": times, "q_W_m2": flux, "error_um": error})
