"""The FE ball screw: closed forms, the axisymmetric body, bearings, the moving nut, configs, data sets."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse.linalg import spsolve

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.fe import parse_config, simulate_config
from groupfit.fe.ballscrew import (
    BallScrewScenario,
    Screw,
    ScrewModel,
    Source,
    simulate_axisymmetric,
    simulate_ballscrew,
    steady_rise_at_source,
)
from groupfit.screw.runs import load_screw_run

ROOT = Path(__file__).resolve().parents[1]


def config(name):
    return tomllib.loads((ROOT / "configs" / f"{name}.toml").read_text())


def test_steady_fin_matches_the_closed_form_profile():
    screw = Screw(diameter=0.02)
    model = ScrewModel(screw, 150)
    theta = spsolve(model.conductance.tocsc(), 2.0 * model.point_load(0.0))
    lam, L = screw.fin_parameter, screw.length
    beta = screw.convection / (screw.conductivity * lam)
    a = 2.0 / (screw.conductivity * screw.area * lam * (math.sinh(lam * L) + beta * math.cosh(lam * L)))
    exact = a * (np.cosh(lam * (L - model.nodes)) + beta * np.sinh(lam * (L - model.nodes)))
    assert np.max(np.abs(theta - exact)) < 1e-4 * exact[0]
    assert theta[0] == pytest.approx(steady_rise_at_source(screw, 2.0), rel=1e-3)


def test_without_convection_the_heat_stored_is_the_heat_put_in():
    screw = Screw(convection=0.0)
    sc = BallScrewScenario(screw=screw, source=Source(power_W=3.0), duration_s=600.0, sensors={"T0mm": 0.0})
    df = simulate_ballscrew(sc, progress=False)
    # elongation a∫θ dx over the whole screw ↔ energy: ρcA∫θ dx = P·t
    model = ScrewModel(screw, sc.elements)
    total = ScrewModel(screw, sc.elements).displacement_weights(screw.length)[0]
    from groupfit.fe.ballscrew import solve_field

    _, times, theta, *_ = solve_field(sc)
    energy = screw.density * screw.heat_capacity * screw.area * (theta @ total) / (1e6 * screw.expansion)
    assert np.allclose(energy, 3.0 * times, rtol=1e-9, atol=1e-9)
    assert model.displacement_weights(0.0)[0].sum() == 0.0
    assert df["error_um"].iloc[0] == 0.0


def test_fin_agrees_with_the_axisymmetric_body():
    raw = config("screw_H")
    raw["time"]["duration_s"] = 1800.0
    raw.pop("noise")
    sc = parse_config(raw)
    fin = simulate_ballscrew(sc, progress=False)
    body = simulate_axisymmetric(sc, axial=150, radial=3)
    names = body["names"]
    rise = fin[names].to_numpy() - 20.0
    assert np.max(np.abs(body["temps"] - fin[names].to_numpy())) < 0.01 * rise.max()
    assert np.max(np.abs(body["error_um"] - fin["error_um"].to_numpy())) < 0.01 * fin["error_um"].max()


def test_fixed_fixed_screw_keeps_its_length():
    screw = Screw(bearings="fixed-fixed")
    model = ScrewModel(screw, 60)
    theta = np.linspace(5.0, 1.0, len(model.nodes))
    assert model.displacement_weights(screw.length)[0] @ theta == pytest.approx(0.0, abs=1e-12)
    free = ScrewModel(Screw(), 60).displacement_weights([0.1, screw.length]) @ theta
    fixed = model.displacement_weights(0.1)[0] @ theta
    assert fixed == pytest.approx(free[0] - 0.1 / screw.length * free[1])
    # exact for a field linear in x: a∫₀ˣ (5 − 4ξ/L) dξ
    x = 0.137
    exact = 1e6 * screw.expansion * (5 * x - 2 * x * x / screw.length)
    assert ScrewModel(Screw(), 60).displacement_weights(x)[0] @ theta == pytest.approx(exact, rel=1e-12)


def test_moving_nut_follows_its_programme_and_heats_by_speed():
    raw = config("screw_nut")
    raw["time"]["duration_s"] = 600.0
    raw.pop("noise")
    df = simulate_config(raw, progress=False)
    assert list(df.columns[-5:]) == ["error_um", "probe_x_m", "power_W", "nut_x_m", "screw_rpm"]
    assert df["nut_x_m"].between(0.05, 0.25).all()
    assert np.array_equal(df["probe_x_m"], df["nut_x_m"])
    moving = df["screw_rpm"] > 0
    assert np.allclose(df.loc[moving, "screw_rpm"] * 0.005 / 60, 0.1 * df.loc[moving, "power_W"] / 1.6)
    # the stroke (50–250 mm) warms: more inside it than at the far end of the sensor row's opposite side
    assert df["T100mm"].iloc[-1] - 20.0 > 0.5
    assert (df["error_um"].iloc[-30:] > 0).all()
    # without convection the heat stored is the heat the nut and the bearing put in
    raw["screw"]["convection_W_m2K"] = 0.0
    from groupfit.fe.ballscrew import solve_field

    sc = parse_config(raw)
    model, times, theta, *_ = solve_field(sc)
    screw = sc.screw
    stored = screw.density * screw.heat_capacity * screw.area * (theta @ model.displacement_weights(screw.length)[0])
    stored /= 1e6 * screw.expansion
    cycle = 2 * (0.2 / 0.1 + 2.0)  # two strokes of 2 s and two dwells of 2 s
    put_in = 1.6 * (2 * 2.0 / cycle) * times  # 1.6 W while moving, moving half the time
    assert stored[-1] == pytest.approx(put_in[-1], rel=0.01)


def test_config_errors_name_the_key():
    raw = config("screw_H")
    raw["screw"]["bearings"] = "floating"
    with pytest.raises(InputError, match="screw.bearings"):
        parse_config(raw)
    raw = config("screw_H")
    raw["probe"]["x_m"] = 0.5
    with pytest.raises(InputError, match="probe.x_m"):
        parse_config(raw)
    raw = config("screw_H")
    raw["screw"]["pitch"] = 1
    with pytest.raises(InputError, match="screw.pitch"):
        parse_config(raw)
    raw = config("screw_H")
    raw["probe"]["x_m"] = "nut"
    with pytest.raises(InputError, match="probe.x_m"):
        parse_config(raw)


def test_shipped_run_H_is_reproduced_byte_for_byte(tmp_path, capsys):
    out = tmp_path / "screw_H.csv"
    assert main(["simulate", str(ROOT / "configs" / "screw_H.toml"), "-o", str(out), "--quiet"]) == 0
    assert out.read_bytes() == (ROOT / "datasets" / "screw_H.csv").read_bytes()


def test_noise_is_seeded_and_quantised():
    raw = config("screw_H")
    raw["time"]["duration_s"] = 300.0
    first, again = simulate_config(raw, progress=False), simulate_config(raw, progress=False)
    assert first.equals(again)
    temps = first["T40mm"].to_numpy()
    assert np.allclose(temps * 100, np.round(temps * 100), atol=1e-6)
    raw["noise"]["seed"] = 99
    assert not simulate_config(raw, progress=False)["T40mm"].equals(first["T40mm"])


def test_displacements_at_further_positions():
    raw = config("screw_H")
    raw["time"]["duration_s"] = 600.0
    raw.pop("noise")
    raw["probe"]["displacements_m"] = [0.16, 0.3]
    df = simulate_config(raw, progress=False)
    assert np.allclose(df["u160mm_um"], df["error_um"])
    assert (df["u300mm_um"] >= df["u160mm_um"]).all()  # the free end moves most
    raw["probe"]["displacements_m"] = [0.4]
    with pytest.raises(InputError, match="probe.displacements_m"):
        parse_config(raw)


def test_a_source_away_from_the_end_gives_the_probe_as_its_distance_from_the_source():
    """The sensors are named by their distance from the source; the probe column is in the same coordinate, so that
    the screw commands read the run as it was simulated. The error is still the displacement at the probe."""
    raw = config("screw_H")
    raw["time"]["duration_s"] = 600.0
    raw.pop("noise")
    start = 0.05
    raw["source"]["x_m"] = start
    raw["sensors"] = {name: x + start for name, x in raw["sensors"].items()}
    raw["probe"]["x_m"] += start
    raw["probe"]["displacements_m"] = [raw["probe"]["x_m"]]
    df = simulate_config(raw, progress=False)
    assert np.allclose(df["probe_x_m"], 0.16)
    assert np.allclose(df["error_um"], df[f"u{1000 * (0.16 + start):g}mm_um"])
    run = load_screw_run(df, name="source_5cm_in")
    assert np.allclose(run.probe_x, 0.16)
