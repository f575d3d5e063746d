"""Effects a sensor model does not declare: the unsensed part, ambient offsets,
and the diagnosis data sets (configs/diag_*.toml)."""

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.errors import InputError
from groupfit.fe import parse_config, simulate_config

ROOT = Path(__file__).resolve().parents[1]
COARSE = {"circumferential": 24, "radial": 3, "axial_spacing_m": 0.07}
BEARING_HEAT_W = 102.0 + 85.4  # at 2000 r/min
TAU_S = 1800.0
GAIN = 0.1


def coarse(**tables):
    return {
        "kind": "headstock",
        "mesh": dict(COARSE),
        "time": {"schedule": [[3600, 2000.0]], "hold_until_equilibrium_rpm": False},
        **tables,
    }


@pytest.fixture(scope="module")
def plain():
    return simulate_config(coarse(), progress=False)


def test_unsensed_part_is_a_first_order_lag_of_the_bearing_heat(plain):
    df = simulate_config(coarse(unsensed_part={"tau_s": TAU_S, "gain_um_per_W": GAIN}), progress=False)
    added = (df["error_um"] - plain["error_um"]).to_numpy()
    t = df["time_s"].to_numpy()
    final = GAIN * BEARING_HEAT_W
    assert added == pytest.approx(final * (1.0 - np.exp(-t / TAU_S)), rel=1e-9, abs=1e-12)
    # a step of heat: 63.2 % of the final value at t = τ
    assert added[t == TAU_S][0] / final == pytest.approx(1.0 - math.exp(-1.0), rel=1e-9)
    # the part is unsensed: the temperatures do not change
    for column in ["T1", "T2", "T3", "T4", "T5", "T6", "T_amb", "spindle_on"]:
        assert np.array_equal(df[column], plain[column])
    assert list(df.columns) == list(plain.columns)


def test_zero_gain_gives_the_error_without_the_table(plain):
    df = simulate_config(coarse(unsensed_part={"tau_s": TAU_S, "gain_um_per_W": 0.0}), progress=False)
    pd.testing.assert_frame_equal(df, plain, check_exact=True)


def test_unsensed_part_fed_by_the_bed_heat_lags_behind_the_housing(plain):
    df = simulate_config(coarse(unsensed_part={"tau_s": TAU_S, "gain_um_per_W": GAIN, "heat": "bed"}), progress=False)
    added = (df["error_um"] - plain["error_um"]).to_numpy()
    # the bed receives part of the bearing heat, later: below the bearing-fed lag
    assert added[0] == 0.0 and np.all(np.diff(added) > 0)
    assert added[-1] < 0.5 * GAIN * BEARING_HEAT_W * (1.0 - math.exp(-3600.0 / TAU_S))


@pytest.mark.parametrize(
    "table, key",
    [
        ({"gain_um_per_W": 0.05}, "unsensed_part.tau_s"),
        ({"tau_s": 3600.0}, "unsensed_part.gain_um_per_W"),
        ({"tau_s": -3600.0, "gain_um_per_W": 0.05}, "unsensed_part.tau_s"),
        ({"tau_s": 3600.0, "gain_um_per_W": "0.05"}, "unsensed_part.gain_um_per_W"),
        ({"tau_s": 3600.0, "gain_um_per_W": 0.05, "heat": "oil"}, "unsensed_part.heat"),
        ({"tau_s": 3600.0, "gain_um_per_W": 0.05, "tua_s": 1.0}, "unsensed_part.tua_s"),
        (3600.0, "unsensed_part"),
    ],
)
def test_unsensed_part_keys_are_validated(table, key):
    with pytest.raises(InputError) as info:
        parse_config({"kind": "headstock", "unsensed_part": table})
    assert f"'{key}'" in str(info.value)


def test_ambient_offsets_add_a_step_to_the_cycle():
    ambient = {
        "profile": "sine",
        "mean_C": 20.0,
        "amplitude_C": 2.0,
        "period_s": 7200.0,
        "offsets": [[1000, 0.0], [100, 1.5]],
    }
    scenario = parse_config({"kind": "headstock", "ambient": ambient})
    for t in [0.0, 400.0, 999.0, 1000.0, 5000.0]:
        expected = 20.0 + 2.0 * math.sin(2 * math.pi * t / 7200.0) + (1.5 if t >= 1000 else 0)
        assert scenario.ambient.temperature(t) == pytest.approx(expected, abs=1e-12)
    misaligned = dict(ambient, offsets=[[1010, 0.0], [100, 1.5]])
    with pytest.raises(InputError, match="'ambient.offsets'"):
        parse_config({"kind": "headstock", "ambient": misaligned})


SCENARIOS = ["ambient", "source", "lag", "none"]


def shortened(config: dict, duration_s: float = 7200.0) -> dict:
    """The config on the coarse mesh, its duty schedule cut to ``duration_s``."""
    short = copy.deepcopy(config)
    short["mesh"] = dict(COARSE)
    steps, left = [], duration_s
    for duration, speed in short["time"]["schedule"]:
        if left <= 0:
            break
        steps.append([min(duration, left), speed])
        left -= duration
    short["time"]["schedule"] = steps
    return short


def load(name: str) -> dict:
    return tomllib.loads((ROOT / "configs" / f"{name}.toml").read_text())


@pytest.mark.parametrize("scenario", ["ambient", "lag"])
def test_a_shortened_diagnosis_config_regenerates_identically(scenario):
    config = shortened(load(f"diag_{scenario}_model"))
    first = simulate_config(config, progress=False)
    again = simulate_config(copy.deepcopy(config), progress=False)
    pd.testing.assert_frame_equal(first, again, check_exact=True)
    assert len(first) == 73


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("run", ["model", "validate"])
def test_diagnosis_data_sets_match_their_configs(scenario, run):
    name = f"diag_{scenario}_{run}"
    scenario_obj = parse_config(load(name))
    df = pd.read_csv(ROOT / "datasets" / f"{name}.csv")
    period = scenario_obj.sampling_period_s
    assert len(df) == round(scenario_obj.spindle.total_duration / period) + 1
    assert np.allclose(np.diff(df["time_s"]), period)
    expected = ["time_s", "T1", "T2", "T3", "T4", "T5", "T6", "T_amb", "error_um", "speed_rpm", "spindle_on"] + [
        f"src_{s.name}_on" for s in scenario_obj.sources
    ]
    assert list(df.columns) == expected
    # exactly one undeclared effect per scenario
    assert (np.ptp(df["T_amb"]) > 0.5) == (scenario == "ambient")  # beyond the sensor noise ([noise])
    assert bool(scenario_obj.sources) == (scenario == "source")
    assert (scenario_obj.unsensed_part is not None) == (scenario == "lag")
    # the runs start cold and at rest: spindle (and source) off in row 0
    noise = scenario_obj.noise.probe_sd_um  # the probe's first reading: zero plus its noise
    assert df["spindle_on"].iloc[0] == 0.0 and abs(df["error_um"].iloc[0]) <= 4 * noise
