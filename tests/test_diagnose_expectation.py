"""The next-run figure ``diagnose`` writes for a grouped model with an added effect is scored as the model is
built: the effect with one coefficient for every group, the breaks those of the measured inputs."""

import json

import numpy as np
import pandas as pd

from groupfit.cli import main

HOUR = 3600.0
PERIOD = 60.0


def lagged(u: np.ndarray, tau_s: float, start: float) -> np.ndarray:
    out, state, a = np.empty_like(u), start, PERIOD / (tau_s + PERIOD)
    for i, x in enumerate(u):
        state += a * (x - state)
        out[i] = state
    return out


def schedule(blocks, n: int) -> np.ndarray:
    values = np.concatenate([np.full(int(hours * HOUR / PERIOD), float(level)) for hours, level in blocks])
    return np.resize(values, n)


def pump_run(
    seed: int, speeds, pumps, air_level: float, swing: float, phase: float, hours: float = 18.0
) -> pd.DataFrame:
    """Three sensors heated by the spindle and the air; the error also follows a coolant pump no sensor sees."""
    rng = np.random.default_rng(seed)
    n = int(hours * HOUR / PERIOD)
    time = np.arange(n) * PERIOD
    air = air_level + swing * np.sin(2 * np.pi * time / 86400.0 + phase) + 0.3 * time / 86400.0
    heat = (schedule(speeds, n) / 1000.0) ** (5 / 3)
    t1 = lagged(air, HOUR, air[0]) + lagged(6 * heat, 2400.0, 0.0)
    t2 = lagged(air, 2 * HOUR, air[0]) + lagged(2.5 * heat, 2 * HOUR, 0.0)
    t3 = lagged(air, 3 * HOUR, air[0]) + lagged(heat, 4 * HOUR, 0.0)
    pump = schedule(pumps, n)
    error = 4.0 * (t1 - 20) + 2.0 * (t2 - 20) - 1.5 * (t3 - 20) + 6.0 * lagged(pump, HOUR, 0.0)
    return pd.DataFrame(
        {
            "time_s": time,
            "T1": np.round(t1 + rng.normal(0, 0.03, n), 2),
            "T2": np.round(t2 + rng.normal(0, 0.03, n), 2),
            "T3": np.round(t3 + rng.normal(0, 0.03, n), 2),
            "T_amb": np.round(air + rng.normal(0, 0.03, n), 2),
            "speed_rpm": schedule(speeds, n),
            "pump_on": pump,
            "error_um": np.round(error + rng.normal(0, 0.1, n), 2),
        }
    )


def test_a_grouped_model_with_an_added_effect_expects_what_its_next_run_shows(tmp_path, capsys):
    pump_run(
        1,
        [(1, 0), (2, 1500), (1, 0), (3, 3000), (1, 0), (2, 2000), (1, 500), (3, 4000), (4, 0)],
        [(2, 0), (3, 1), (2, 0), (4, 1), (7, 0)],
        20.0,
        2.0,
        0.0,
    ).to_csv(tmp_path / "a.csv", index=False)
    pump_run(
        2,
        [(0.5, 0), (3, 2500), (1.5, 0), (2, 3500), (1, 1000), (2, 0), (4, 2000), (4, 0)],
        [(1, 0), (2, 1), (3, 0), (5, 1), (7, 0)],
        22.0,
        3.0,
        1.5,
    ).to_csv(tmp_path / "b.csv", index=False)
    a, b = str(tmp_path / "a.csv"), str(tmp_path / "b.csv")
    assert main(["fit", "--data", a, "--p", "1", "--quiet", "--out", str(tmp_path / "m")]) == 0
    assert (
        main(
            [
                "diagnose",
                str(tmp_path / "m" / "model.json"),
                "--data",
                a,
                "--quiet",
                "--json",
                str(tmp_path / "d.json"),
                "--out",
                str(tmp_path / "d"),
            ]
        )
        == 0
    )
    augmented = json.loads((tmp_path / "d" / "model_augmented.json").read_text())
    assert augmented["p"] == 1 and any("pump_on" in name for name in augmented["temps"])
    shared = [k for k, name in enumerate(augmented["temps"]) if "pump_on" in name]
    coefficients = np.array(augmented["coefficients"])[:, [1 + k for k in shared]]
    np.testing.assert_allclose(coefficients, np.repeat(coefficients[:1], len(coefficients), axis=0))  # shared
    expected = augmented["training"]["expected_next_run_rms_um"]
    capsys.readouterr()
    assert main(["replay", str(tmp_path / "d" / "model_augmented.json"), "--data", b, "--json", "-"]) == 0
    actual = json.loads(capsys.readouterr().out)["rms_um"]
    before = json.loads((tmp_path / "m" / "model.json").read_text())["training"]["expected_next_run_rms_um"]
    assert expected < before
    assert 0.25 < actual / expected < 4.0, (expected, actual)  # was about 83 µm expected against 0.7 µm
