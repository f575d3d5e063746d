"""End-to-end runs of simulate_config on a coarse housing mesh."""

import math

import numpy as np
import pandas as pd
import pytest

from groupfit.fe import plot_dataset, simulate_config
from groupfit.fe.config import Material, ThermalBoundary
from groupfit.fe.geometry import FRONT_SEAT, REAR_SEAT, HousingGeometry, MeshResolution, build_housing_mesh
from groupfit.fe.headstock import ThermalModel, ThermoElasticModel, nose_error_gain

COARSE = {"circumferential": 24, "radial": 3, "axial_spacing_m": 0.07}


def coarse(**tables):
    return {"kind": "headstock", "mesh": dict(COARSE), **tables}


SHORT = coarse(time={"schedule": [[600, 2000.0], [300, 0.0], [300, 1500.0]], "hold_until_equilibrium_rpm": False})


@pytest.fixture(scope="module")
def short_run():
    return simulate_config(SHORT, progress=False)


def test_same_config_gives_identical_numbers(short_run):
    again = simulate_config(SHORT, progress=False)
    pd.testing.assert_frame_equal(short_run, again, check_exact=True)


def test_columns_time_axis_and_conditions(short_run):
    df = short_run
    assert list(df.columns) == [
        "time_s",
        "T1",
        "T2",
        "T3",
        "T4",
        "T5",
        "T6",
        "T_amb",
        "error_um",
        "speed_rpm",
        "spindle_on",
    ]
    assert np.array_equal(df["time_s"], np.arange(13) * 100.0)
    # row k holds the condition of the interval ending at sample k
    assert list(df["speed_rpm"]) == [2000.0] * 7 + [0.0] * 3 + [1500.0] * 3
    assert list(df["spindle_on"]) == [1.0] * 7 + [0.0] * 3 + [1.0] * 3
    assert (df["T_amb"] == 20.0).all()
    assert df["error_um"].iloc[0] == 0.0
    # heating raises the error; it falls in the stop; the sensor by the front
    # bearing reacts faster than the one near the bed
    error = df["error_um"].to_numpy()
    assert np.all(np.diff(error[:7]) > 0) and error[9] < error[6]
    assert df["T1"].iloc[3] - 20.0 > 5 * (df["T6"].iloc[3] - 20.0)


def test_hold_stops_at_the_stated_equilibrium_near_steady_state():
    df = simulate_config(coarse(), progress=False)
    error = df["error_um"].to_numpy()
    span = error.max() - error.min()
    assert abs(error[-1] - error[-37]) <= 0.005 * span  # rule met at the end
    assert abs(error[-2] - error[-38]) > 0.005 * np.ptp(error[:-1])  # not one sample earlier
    assert df["time_s"].iloc[-1] < 172800.0

    housing = build_housing_mesh(
        HousingGeometry(), MeshResolution(**{"circumferential": 24, "radial": 3, "axial_spacing": 0.07})
    )
    thermal = ThermalModel(housing, Material(), ThermalBoundary())
    gain = nose_error_gain(thermal, ThermoElasticModel(thermal.basis, Material()), (0, 1, 0))
    steady = gain @ (thermal.steady_temperature({FRONT_SEAT: 102.0, REAR_SEAT: 85.4}, 20.0) - 20)
    assert error[-1] == pytest.approx(steady, rel=0.03)
    assert error[-1] < steady


def test_ambient_step_without_heat_settles_at_the_new_ambient():
    df = simulate_config(
        coarse(
            ambient={"profile": "steps", "steps": [[100, 20.0], [100, 23.0]]},
            time={"schedule": [[200, 0.0]], "hold_until_equilibrium_rpm": 0.0},
        ),
        progress=False,
    )
    assert df["T_amb"].iloc[0] == 20.0 and df["T_amb"].iloc[-1] == 23.0
    last = df.iloc[-1]
    for sensor in ["T1", "T2", "T3", "T4", "T5", "T6"]:
        assert last[sensor] == pytest.approx(23.0, abs=0.1)
    assert last["error_um"] > 0.0


def test_sine_ambient_and_extra_source_columns():
    df = simulate_config(
        coarse(
            ambient={"profile": "sine", "mean_C": 21.0, "amplitude_C": 2.0, "period_s": 3600.0},
            time={"schedule": [[1200, 2000.0]], "hold_until_equilibrium_rpm": False},
            sources=[
                {
                    "name": "motor",
                    "power_W": 200.0,
                    "region_m": [[0.08, 0.32], [0.18, 0.42], [0.0, 0.0]],
                    "schedule": [[600, 0.0], [300, 1.0]],
                    "repeat": True,
                }
            ],
        ),
        progress=False,
    )
    expected = 21.0 + 2.0 * np.sin(2 * math.pi * df["time_s"] / 3600.0)
    assert np.allclose(df["T_amb"], expected)
    assert list(df["src_motor_on"]) == [0.0] * 7 + [1.0] * 3 + [0.0] * 3
    # the motor flange heats the rear face: the rear-face sensor warms faster
    # while it is on than the same run without the motor
    plain = simulate_config(
        coarse(
            ambient={"profile": "sine", "mean_C": 21.0, "amplitude_C": 2.0, "period_s": 3600.0},
            time={"schedule": [[1200, 2000.0]], "hold_until_equilibrium_rpm": False},
        ),
        progress=False,
    )
    assert "src_motor_on" not in plain
    assert np.allclose(df["T5"].iloc[:7], plain["T5"].iloc[:7])
    assert df["T5"].iloc[9] > plain["T5"].iloc[9] + 0.5


def test_candidate_node_columns_hold_the_nodal_temperatures():
    housing = build_housing_mesh(HousingGeometry(), MeshResolution(24, 3, 0.07))
    first_surface_node = housing.surface_nodes[0]
    probe_at_node = housing.mesh.p[:, first_surface_node].tolist()
    df = simulate_config(
        coarse(
            time={"schedule": [[300, 2000.0]], "hold_until_equilibrium_rpm": False},
            sensors={"P": probe_at_node},
            candidates={"nodes": "surface", "max_count": 25},
        ),
        progress=False,
    )
    nodes = [c for c in df.columns if c.startswith("node_")]
    assert len(nodes) == 25 and nodes[0] == f"node_{first_surface_node}"
    assert np.allclose(df[nodes[0]], df["P"], atol=1e-9)
    assert df[nodes].iloc[-1].max() > 20.5


def test_plot_dataset_writes_png(short_run, tmp_path):
    path = tmp_path / "run.png"
    plot_dataset(short_run, path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
