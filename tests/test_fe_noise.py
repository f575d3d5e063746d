"""Realistic FE runs: seeded sensor and probe noise, quantisation, ambient drift, a warm start."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_fe_simulate import SHORT, coarse

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.fe import parse_config, simulate_config

ROOT = Path(__file__).resolve().parents[1]
NOISE = {
    "sensor_sd_K": 0.03,
    "sensor_resolution_K": 0.01,
    "probe_sd_um": 0.1,
    "probe_resolution_um": 0.01,
    "seed": 5,
}
SENSORS = ["T1", "T2", "T3", "T4", "T5", "T6", "T_amb"]


@pytest.fixture(scope="module")
def exact_and_noisy():
    return simulate_config(SHORT, progress=False), simulate_config({**SHORT, "noise": NOISE}, progress=False)


def test_noise_is_seeded_quantised_and_only_on_the_measured_columns(exact_and_noisy):
    exact, noisy = exact_and_noisy
    again = simulate_config({**SHORT, "noise": dict(NOISE)}, progress=False)
    pd.testing.assert_frame_equal(noisy, again, check_exact=True)
    other = simulate_config({**SHORT, "noise": {**NOISE, "seed": 6}}, progress=False)
    assert not np.array_equal(other["T1"], noisy["T1"])
    temps = noisy[SENSORS].to_numpy()
    assert np.allclose(temps * 100, np.round(temps * 100), atol=1e-6)  # 0.01 K steps
    deviation = temps - exact[SENSORS].to_numpy()
    assert 0.015 < deviation.std() < 0.045 and np.abs(deviation).max() < 0.2
    probe = noisy["error_um"] - exact["error_um"]
    assert 0.05 < probe.std() < 0.15
    for column in ("time_s", "speed_rpm", "spindle_on"):
        assert np.array_equal(noisy[column], exact[column])


def test_ambient_drift_moves_the_ambient_and_the_machine():
    drifted = simulate_config({**SHORT, "noise": {"ambient_drift_K_per_h": 1.0}}, progress=False)
    hours = drifted["time_s"] / 3600.0
    np.testing.assert_allclose(drifted["T_amb"], 20.0 + hours, atol=1e-9)
    assert drifted["T6"].iloc[-1] > simulate_config(SHORT, progress=False)["T6"].iloc[-1] + 0.02


def test_a_warm_start_begins_above_ambient_with_an_error():
    config = coarse(
        time={"schedule": [[600, 2000.0]], "prerun": [[1800, 2000.0], [600, 0.0]], "hold_until_equilibrium_rpm": False}
    )
    warm = simulate_config(config, progress=False)
    assert warm["T1"].iloc[0] > 20.5 and abs(warm["error_um"].iloc[0]) > 0.5
    assert warm["time_s"].iloc[0] == 0.0 and warm["T_amb"].iloc[0] == 20.0


@pytest.mark.parametrize(
    "table, message",
    [
        ({"sensor_sd_K": -0.1}, "sensor_sd_K"),
        ({"seed": -1}, "seed"),
        ({"probe_noise": 0.1}, "probe_noise"),
    ],
)
def test_bad_noise_keys_are_named(table, message):
    with pytest.raises(InputError, match=message):
        parse_config({**SHORT, "noise": table})


def test_the_shipped_headstock_configs_state_realistic_noise():
    from groupfit.tomlconfig import read_toml

    for name in ("paper_cycle", "validation_speed", "validation_timing", "repeat_timing", "repeat_ambient25"):
        noise = parse_config(read_toml(ROOT / "configs" / f"{name}.toml", "config")).noise
        assert noise.sensor_sd_K == 0.03 and noise.sensor_resolution_K == 0.01
        assert noise.probe_sd_um == 0.1 and noise.probe_resolution_um == 0.01


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper_cycle", "repeat_warm"])
def test_a_shipped_headstock_data_set_is_regenerated_byte_for_byte(tmp_path, capsys, name):
    out = tmp_path / f"{name}.csv"
    assert main(["simulate", str(ROOT / "configs" / f"{name}.toml"), "--out", str(out), "--quiet"]) == 0
    assert out.read_bytes() == (ROOT / "datasets" / f"{name}.csv").read_bytes()
