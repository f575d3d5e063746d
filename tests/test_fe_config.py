"""Config validation raises InputError naming the offending key."""

import pytest

from groupfit.errors import InputError
from groupfit.fe import parse_config, simulate_config


def headstock(**tables):
    return {"kind": "headstock", **tables}


@pytest.mark.parametrize(
    "config, key",
    [
        (headstock(housing={"widht_m": 0.4}), "housing.widht_m"),
        (headstock(colour="red"), "colour"),
        (headstock(time={"schedule": [[3000, 2000.0], [-100, 0.0]]}), "time.schedule"),
        (headstock(time={"sampling_period_s": "100"}), "time.sampling_period_s"),
        (headstock(mesh={"radial": 2.5}), "mesh.radial"),
        (headstock(time={"schedule": [[3010, 2000.0]]}), "time.schedule"),
        (headstock(sensors={"T1": [0.2, 0.3, 0.25]}), "sensors.T1"),
        (headstock(sensors={"error_um": [0.2, 0.1, 0.25]}), "sensors.error_um"),
        (headstock(ambient={"profile": "daily"}), "ambient.profile"),
        (
            headstock(sources=[{"name": "motor", "power_W": 50.0, "region_m": [[0, 0.1], [0, 0.1]]}]),
            "sources[1].region_m",
        ),
        (
            headstock(
                sources=[
                    {
                        "name": "motor",
                        "power_W": 50.0,
                        "region_m": [[0, 0.4], [0, 0.1], [0, 0.1]],
                        "schedule": [[100, 2.0]],
                    }
                ]
            ),
            "sources[1].schedule",
        ),
        ({"kind": "rod", "rod": {"radius_m": -0.1}}, "rod.radius_m"),
        ({"kind": "rod", "time": {"schedule": [[0, 2000.0]]}}, "time.schedule"),
        ({"kind": "beam"}, "kind"),
        ({"kind": 3}, "kind"),
    ],
)
def test_bad_config_raises_input_error_naming_the_key(config, key):
    with pytest.raises(InputError) as info:
        parse_config(config)
    message = str(info.value)
    assert f"'{key}'" in message
    assert "\n" not in message


def test_negative_duration_message_says_what_to_do():
    with pytest.raises(InputError, match="positive"):
        simulate_config(headstock(time={"schedule": [[-3000, 2000.0]]}), progress=False)


def test_source_region_off_the_surface_is_reported():
    config = headstock(
        mesh={"circumferential": 16, "radial": 2, "axial_spacing_m": 0.1},
        time={"schedule": [[100, 2000.0]], "hold_until_equilibrium_rpm": False},
        sources=[{"name": "nut", "power_W": 10.0, "region_m": [[0.1, 0.12], [0.1, 0.12], [0.2, 0.22]]}],
    )
    with pytest.raises(InputError, match="nut"):
        simulate_config(config, progress=False)


def test_defaults_parse_to_the_paper_values():
    scenario = parse_config({"kind": "headstock"})
    assert scenario.bearings.front_W == 102.0 and scenario.bearings.rear_W == 85.4
    assert scenario.material.conductivity == 46.4
    assert scenario.boundary.convection == 10.0
    assert [s for s in scenario.spindle.steps] == [(3000.0, 2000.0), (1000.0, 0.0), (4000.0, 2000.0), (1000.0, 0.0)]
