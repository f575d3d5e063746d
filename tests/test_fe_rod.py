"""The FE spindle rod reproduces the closed-form AR(1) law of docs/methods.md §2."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from groupfit.fe import simulate_config

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "rod_ar1.toml"


@pytest.fixture(scope="module")
def rod_run():
    config = tomllib.loads(CONFIG.read_text())
    return config, simulate_config(config, progress=False)


def closed_form(config, q):
    rod, dtau = config["rod"], config["time"]["sampling_period_s"]
    rho_c = rod["density_kg_m3"] * rod["heat_capacity_J_kgK"]
    b = 2 * rod["convection_W_m2K"] / (rho_c * rod["radius_m"])
    c1 = math.exp(-b * dtau)
    return c1, 1e6 * q * rod["expansion_1_K"] / (rho_c * b) * (1 - c1)


def test_closed_form_matches_the_paper_numbers(rod_run):
    config, _ = rod_run
    c1, c2_2000 = closed_form(config, 2000.0)
    assert c1 == pytest.approx(0.9909, abs=5e-5)
    assert c2_2000 == pytest.approx(0.1985, abs=5e-4)
    assert closed_form(config, 3000.0)[1] == pytest.approx(0.2977, abs=5e-4)


def test_least_squares_ar1_fit_recovers_closed_form_coefficients(rod_run):
    config, df = rod_run
    e, q = df["error_um"].to_numpy(), df["q_W_m2"].to_numpy()
    # E(k) = C1 E(k-1) + sum over flux levels of C2(level)·[q_k == level]
    levels = np.unique(q[1:])
    design = np.column_stack([e[:-1]] + [(q[1:] == lv).astype(float) for lv in levels])
    coef, *_ = np.linalg.lstsq(design, e[1:], rcond=None)
    fitted = dict(zip(levels, coef[1:]))
    c1, c2_2000 = closed_form(config, 2000.0)
    c2_3000 = closed_form(config, 3000.0)[1]
    assert coef[0] == pytest.approx(c1, rel=0.02)
    assert fitted[2000.0] == pytest.approx(c2_2000, rel=0.02)
    assert fitted[3000.0] == pytest.approx(c2_3000, rel=0.02)
    assert abs(fitted[0.0]) < 1e-3


def test_rod_columns_and_duty(rod_run):
    _, df = rod_run
    assert list(df.columns) == ["time_s", "q_W_m2", "error_um"]
    assert len(df) == 24 * 120 + 1
    assert np.allclose(np.diff(df["time_s"]), 30.0)
    # heating ends after 4 h: the elongation peaks at sample 480 in the first period
    assert int(np.argmax(df["error_um"].to_numpy()[:600])) == 480
