"""Physics checks of the headstock model against independent truths."""

import numpy as np
import pytest

from groupfit.fe.config import Material, ThermalBoundary
from groupfit.fe.geometry import FRONT_SEAT, REAR_SEAT, HousingGeometry, MeshResolution, build_housing_mesh
from groupfit.fe.headstock import ThermalModel, ThermoElasticModel, nose_error_gain
from groupfit.fe.schedule import bearing_heat_W

GEOMETRY = HousingGeometry()
MATERIAL = Material()


@pytest.fixture(scope="module")
def models():
    housing = build_housing_mesh(GEOMETRY, MeshResolution(24, 3, 0.07))
    thermal = ThermalModel(housing, MATERIAL, ThermalBoundary())
    elastic = ThermoElasticModel(thermal.basis, MATERIAL)
    return housing, thermal, elastic


def test_mesh_volume_and_seat_areas_match_the_drawing(models):
    housing, thermal, _ = models
    g = GEOMETRY
    volume = g.width * g.height * g.length - np.pi * g.bore_radius**2 * g.length
    assert thermal.basis.dx.sum() == pytest.approx(volume, rel=0.01)
    seat = np.pi * g.bore_diameter * (g.front_seat[1] - g.front_seat[0])
    assert thermal.area(thermal.facet_bases[FRONT_SEAT]) == pytest.approx(seat, rel=0.01)


def test_steady_state_energy_balance(models):
    _, thermal, _ = models
    heat = {FRONT_SEAT: 102.0, REAR_SEAT: 85.4}
    temperature = thermal.steady_temperature(heat, ambient_C=20.0)
    heat_in = sum(q * thermal.heat_in_W(name) for name, q in heat.items())
    heat_out = thermal.heat_out_W(temperature, ambient_C=20.0)
    assert heat_in == pytest.approx(187.4, rel=1e-9)
    assert sum(heat_out.values()) == pytest.approx(heat_in, rel=0.01)
    assert all(q > 0 for q in heat_out.values())
    # a hotter housing, but not absurdly: the seats end up a few to tens of kelvin up
    assert 2.0 < temperature.max() - 20.0 < 50.0


def test_free_body_expands_by_alpha_length_delta_t(models):
    housing, thermal, elastic = models
    mesh, g = housing.mesh, GEOMETRY
    x, y, z = mesh.p
    tol = 1e-9
    # symmetry rollers on x = 0, y = 0 and z = 0 leave the body free to expand
    fixed = np.concatenate([elastic.node_dofs(np.flatnonzero(abs(c) < tol), k) for k, c in enumerate((x, y, z))])
    delta_t = 15.0
    u = elastic.displacement(np.full(thermal.basis.N, delta_t), fixed_dofs=fixed)
    ux, uy, uz = (u[elastic.basis.nodal_dofs[k]] for k in range(3))
    alpha = MATERIAL.expansion
    growth_x = ux[abs(x - g.width) < tol].mean()
    growth_y = uy[abs(y - g.height) < tol].mean()
    growth_z = uz[abs(z - g.length) < tol].mean()
    assert growth_x == pytest.approx(alpha * g.width * delta_t, rel=1e-6)
    assert growth_y == pytest.approx(alpha * g.height * delta_t, rel=1e-6)
    assert growth_z == pytest.approx(alpha * g.length * delta_t, rel=1e-6)
    assert np.allclose(uy, alpha * delta_t * y, atol=1e-12)


def test_adjoint_functional_equals_direct_thermoelastic_solve(models):
    housing, thermal, elastic = models
    temperature = thermal.steady_temperature({FRONT_SEAT: 102.0, REAR_SEAT: 85.4}, 20.0)
    delta_t = temperature - 20.0
    for direction in [(0.0, 1.0, 0.0), (0.6, 0.8, 0.0)]:
        gain = nose_error_gain(thermal, elastic, direction)
        u = elastic.displacement(delta_t)
        nose_u = [u[elastic.basis.nodal_dofs[k, housing.nose_nodes]] for k in range(3)]
        axis_shift = sum(d * housing.nose_weights @ nose_u[k] for k, d in enumerate(direction))
        assert gain @ delta_t == pytest.approx(1e6 * axis_shift, rel=1e-7)


def test_error_sign_and_symmetry(models):
    _, thermal, elastic = models
    rise = nose_error_gain(thermal, elastic, (0.0, 1.0, 0.0)).sum() * 10.0
    sideways = nose_error_gain(thermal, elastic, (1.0, 0.0, 0.0)).sum() * 10.0
    free_rise = 1e6 * MATERIAL.expansion * 10.0 * GEOMETRY.axis_height
    # uniform heating lifts the axis by about alpha·h·dT (more with the clamped
    # base's Poisson restraint) and, the housing being symmetric, not sideways
    assert free_rise < rise < 1.3 * free_rise
    assert abs(sideways) < 1e-6 * rise


def test_palmgren_speed_law():
    assert bearing_heat_W(102.0, 2000.0) == pytest.approx(102.0)
    assert bearing_heat_W(102.0, 1000.0) == pytest.approx(102.0 * 0.5 ** (5 / 3))
    assert bearing_heat_W(102.0, 0.0) == 0.0
    assert bearing_heat_W(102.0, 3000.0, exponent=1.0) == pytest.approx(153.0)
