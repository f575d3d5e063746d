"""One uniform refinement changes the equilibrium thermal error by < 2 %."""

import pytest

from groupfit.fe.config import Material, ThermalBoundary
from groupfit.fe.geometry import FRONT_SEAT, REAR_SEAT, HousingGeometry, MeshResolution, build_housing_mesh
from groupfit.fe.headstock import ThermalModel, ThermoElasticModel, nose_error_gain


def equilibrium_error_um(resolution):
    housing = build_housing_mesh(HousingGeometry(), resolution)
    thermal = ThermalModel(housing, Material(), ThermalBoundary())
    elastic = ThermoElasticModel(thermal.basis, Material())
    gain = nose_error_gain(thermal, elastic, (0.0, 1.0, 0.0))
    temperature = thermal.steady_temperature({FRONT_SEAT: 102.0, REAR_SEAT: 85.4}, 20.0)
    return float(gain @ (temperature - 20.0))


@pytest.mark.slow
def test_refinement_changes_equilibrium_error_by_less_than_two_percent():
    coarse = equilibrium_error_um(MeshResolution(24, 3, 0.07))
    fine = equilibrium_error_um(MeshResolution(24, 3, 0.07, refinements=1))
    assert 10.0 < fine < 60.0
    assert abs(coarse - fine) / abs(fine) < 0.02
