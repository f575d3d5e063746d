"""Position-dependent models: K0 + tanβ·(P − P0), polynomials, tables and the dead band, in every target."""

from __future__ import annotations

import json
import shutil
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest
from support.json_runtime import compensation, run_table
from support.replay import assert_same_decisions, python_replay

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.export import render, write
from groupfit.export.harness import build_driver, run_driver
from groupfit.export.table import position_coefficients, position_table, table_error
from groupfit.model import ModelFile, model_file_problem
from groupfit.models import GroupedRegressor
from groupfit.position import cross_validate_order, fit_blocks, load_position_run, wide_to_long, with_position
from groupfit.runtime import FAULT_POSITION, FAULT_SENSOR, RuleTables, SwitchingRule

POSITIONS = np.linspace(0.0, 1000.0, 11)
P0 = 500.0


def thermal_states(n: int = 48, period: float = 1200.0):
    """Warm-up for 2/3 of the run, then cool-down: time, T1 (near the screw), T2 (the bed), T_amb."""
    t = np.arange(n) * period
    on = t < (2 * n // 3) * period
    rise1 = np.where(on, 12 * (1 - np.exp(-t / 9000)), 0.0)
    stop = (2 * n // 3) * period
    peak1 = 12 * (1 - np.exp(-stop / 9000))
    rise1 = np.where(on, rise1, peak1 * np.exp(-(t - stop) / 7000))
    rise2 = np.where(on, 5 * (1 - np.exp(-t / 20000)), 5 * (1 - np.exp(-stop / 20000)) * np.exp(-(t - stop) / 15000))
    return t, 20 + rise1, 21 + rise2 + 0.2 * np.sin(t / 4000), np.full(n, 20.0)


def truth(order: int, d: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """A screw growing from its fixed bearing: offset and slope with the rises, curvature for order ≥ 2."""
    error = 1.2 * r1 + 0.4 * r2 + (0.011 * r1 + 0.003 * r2) * d
    if order >= 2:
        error = error + 4e-6 * r1 * d**2
    if order >= 3:
        error = error + 2.5e-8 * (r1 + r2) * d**3
    return error


def long_table(order: int = 1, noise: float = 0.1, seed: int = 0, positions=POSITIONS) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    t, t1, t2, amb = thermal_states()
    rows = []
    for i in range(len(t)):
        d = positions - P0
        error = truth(order, d, np.full(len(d), t1[i] - 20), np.full(len(d), t2[i] - 21))
        error = error + rng.normal(0, noise, len(d))
        for p, e in zip(positions, error):
            rows.append((t[i], p, t1[i], t2[i], amb[i], e))
    return pd.DataFrame(rows, columns=["time_s", "P_mm", "T1", "T2", "T_amb", "error_um"])


def fitted(order: int = 1, fit_order: int | None = None, p: int = 0, dead_band=None, noise: float = 0.1):
    run = load_position_run(long_table(order, noise), "P_mm", temps=["T1", "T2"])
    estimator = GroupedRegressor(p=p, search="exact").fit(run.run.temps, run.run.error)
    model = with_position(estimator.to_model_file(run.run), run, fit_order or order, P0, dead_band=dead_band)
    return model.checked(), run


@lru_cache(maxsize=None)
def model_dict(order: int, p: int, dead_band: bool) -> dict:
    from groupfit.model import DeadBand

    band = DeadBand(reference="T_amb", threshold_c=1.0) if dead_band else None
    return fitted(order, p=p, dead_band=band)[0].to_dict()


def model_for(order: int, p: int = 1, dead_band: bool = False) -> dict:
    return json.loads(json.dumps(model_dict(order, p, dead_band)))


def per_row_errors(model: ModelFile, run) -> np.ndarray:
    groups = model.serving_groups(run.run.n_samples)[run.check]
    return run.error - model.predict_position(run.inputs(), run.position, groups)


# --------------------------------------------------------------------- the fit


def rms_max(residuals: np.ndarray) -> tuple[float, float]:
    return float(np.sqrt(np.mean(residuals**2))), float(np.max(np.abs(residuals)))


def test_the_position_model_beats_the_position_free_model_at_the_axis_ends():
    model, run = fitted(1)
    free = fit_blocks(run.inputs(), np.zeros(len(run.position)), run.error, 0)[0]
    free_residuals = run.error - (free[0] + run.inputs() @ free[1:])
    residuals = per_row_errors(model, run)
    for end in (POSITIONS[0], POSITIONS[-1]):
        at = run.position == end
        rms, largest = rms_max(residuals[at])
        free_rms, free_max = rms_max(free_residuals[at])
        assert rms < 0.25 * free_rms and largest < 0.25 * free_max
        assert rms < 0.2  # the noise is 0.1 µm
    assert model.position.order == 1 and model.position.p0_mm == P0


def test_a_polynomial_beats_k0_plus_tanb_where_the_error_is_curved():
    linear, run = fitted(3, fit_order=1)
    cubic, _ = fitted(3, fit_order=3)
    assert rms_max(per_row_errors(cubic, run))[0] < 0.5 * rms_max(per_row_errors(linear, run))[0]
    assert rms_max(per_row_errors(cubic, run))[1] < 0.5 * rms_max(per_row_errors(linear, run))[1]


@pytest.mark.parametrize("order", [1, 2, 3])
def test_order_selection_over_held_out_positions_picks_the_truth(order):
    run = load_position_run(long_table(order, noise=0.1, seed=order), "P_mm", temps=["T1", "T2"])
    chosen = cross_validate_order(run, max_order=5, p0=P0)
    assert chosen["order"] == order
    assert chosen["folds"] == "held-out positions"


def test_grouped_position_models_keep_the_groups_of_the_check_runs():
    model, run = fitted(2, p=1)
    assert model.p == 1 and len(model.position.coefficients) == 2
    assert rms_max(per_row_errors(model, run))[0] < 0.2


# --------------------------------------------------------------------- the data


def test_wide_and_long_tables_are_the_same_run(tmp_path):
    long = long_table(1)
    wide = long.pivot(index="time_s", columns="P_mm", values="error_um")
    wide.columns = [f"err_P{int(p):04d}" for p in wide.columns]
    temps = long.groupby("time_s")[["T1", "T2", "T_amb"]].first()
    wide = temps.join(wide).reset_index()
    wide.to_csv(tmp_path / "wide.csv", index=False)
    from_wide = load_position_run(tmp_path / "wide.csv", "P_mm", temps=["T1", "T2"])
    from_long = load_position_run(long, "P_mm", temps=["T1", "T2"])
    assert np.array_equal(from_wide.position, from_long.position)
    assert np.allclose(from_wide.error, from_long.error) and np.array_equal(from_wide.check, from_long.check)
    assert list(wide_to_long(wide, "P_mm").columns) == ["time_s", "T1", "T2", "T_amb", "P_mm", "error_um"]


def test_an_implausible_error_is_named_by_its_row_and_column_in_the_file(tmp_path):
    """Rows counted from 1 as in every refusal, in the file's order (not the order by time the run is read in),
    and in a wide table the err_P<mm> column that holds it."""
    shuffled = long_table(1).sample(frac=1.0, random_state=3).reset_index(drop=True)
    shuffled.loc[17, "error_um"] = 2.5e5
    shuffled.to_csv(tmp_path / "long.csv", index=False)
    with pytest.raises(InputError, match=r"row 18, column 'error_um': 250000 µm is beyond the plausible ±100000 µm"):
        load_position_run(tmp_path / "long.csv", "P_mm", temps=["T1", "T2"])
    assert load_position_run(tmp_path / "long.csv", "P_mm", temps=["T1", "T2"], error_limit=1e6).run.n_samples == 48
    long = long_table(1)
    wide = long.pivot(index="time_s", columns="P_mm", values="error_um")
    wide.columns = [f"err_P{int(p):04d}" for p in wide.columns]
    wide = long.groupby("time_s")[["T1", "T2", "T_amb"]].first().join(wide).reset_index()
    wide.loc[5, "err_P0300"] = -3e5
    wide.to_csv(tmp_path / "wide.csv", index=False)
    with pytest.raises(InputError, match=r"row 6, column 'err_P0300': -300000 µm is beyond"):
        load_position_run(tmp_path / "wide.csv", "P_mm", temps=["T1", "T2"])


def test_a_long_table_is_checked_for_uniform_sampling_per_check_run_not_per_row():
    long = long_table(1)
    run = load_position_run(long.sample(frac=1.0, random_state=3), "P_mm", temps=["T1", "T2"])
    assert run.run.n_samples == 48 and run.run.period == 1200.0
    gap = long[long.time_s != 1200.0 * 7]
    with pytest.raises(InputError, match="not uniform"):
        load_position_run(gap, "P_mm", temps=["T1", "T2"])


def test_a_missing_or_non_numeric_position_column_is_named():
    long = long_table(1)
    with pytest.raises(InputError, match="position column 'X_mm' not found"):
        load_position_run(long, "X_mm", temps=["T1", "T2"])
    bad = long.astype({"P_mm": object})
    bad.loc[5, "P_mm"] = "left end"
    with pytest.raises(InputError, match="P_mm"):
        load_position_run(bad, "P_mm", temps=["T1", "T2"])
    one = long[long.P_mm == 0.0]
    with pytest.raises(InputError, match="one position"):
        load_position_run(one, "P_mm", temps=["T1", "T2"])


@pytest.mark.parametrize("column", ["P_mm", "error_um"])
def test_an_empty_position_or_error_cell_is_named_without_advice_a_position_fit_refuses(column, tmp_path, capsys):
    long = long_table(1)
    long.loc[5, column] = np.nan
    long.to_csv(tmp_path / "holes.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "holes.csv"), "--temps", "T1,T2", "--position", "P_mm", "--p", "0"]
    assert main([*args, "--out", str(tmp_path / "m"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"row 6, column '{column}' is empty" in err[0]
    assert "--resample" not in err[0]
    assert main([*args, "--resample", "1200", "--out", str(tmp_path / "m"), "--quiet"]) == 2  # refused as advised
    assert "leave --resample out" in capsys.readouterr().err


# --------------------------------------------------------------------- the model file


def test_old_files_load_unchanged_and_the_position_section_round_trips():
    model = model_for(1)
    assert "position" in model and ModelFile.from_dict(model).to_dict() == model
    plain = GroupedRegressor(p=0).fit(np.arange(20.0)[:, None], np.arange(20.0))
    assert plain.coef_.shape == (1, 1)
    old = {k: v for k, v in model.items() if k not in ("position", "dead_band")}
    assert ModelFile.from_dict(old).position is None


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda s: s.pop("column"), "lacks key 'column'"),
        (lambda s: s.update(column="T1"), "also a model input"),
        (lambda s: s.update(column="T_amb"), "also the reference"),
        (lambda s: s.update(order=0), "position.order"),
        (lambda s: s.update(travel_mm=[5.0, 5.0]), "travel_mm"),
        (lambda s: s.update(p0_mm=float("nan")), "p0_mm"),
        (lambda s: s["coefficients"][0].pop(), "row"),
        (lambda s: s["coefficients"][0][0].append(1.0), "finite numbers"),
        (lambda s: s["coefficients"].pop(), "one entry per group"),
    ],
)
def test_a_bad_position_section_is_refused(change, message):
    model = model_for(1)
    model["reference"] = "T_amb"
    assert model_file_problem(model) is None
    change(model["position"])
    problem = model_file_problem(model)
    assert problem is not None and message in problem


def test_the_band_stream_goes_in_and_out_of_the_dead_band():
    model = model_for(3, p=1, dead_band=True)
    band = streams(model)["dead band"]
    replay = SwitchingRule(model).replay(band)
    held = np.flatnonzero(np.diff(replay.compensation_um) == 0)
    assert 10 < held.size < len(band) - 10


def test_a_bad_dead_band_is_refused():
    model = model_for(1, dead_band=True)
    assert model_file_problem(model) is None
    model["dead_band"]["threshold_c"] = 0.0
    assert "dead_band.threshold_c" in model_file_problem(model)


# --------------------------------------------------------------------- the run-time rule


def streams(model: dict, seed: int = 0) -> dict[str, np.ndarray]:
    """Readings per sample with the axis anywhere (also outside the travel), and faults."""
    tables = RuleTables.from_model(model)
    t, t1, t2, amb = thermal_states()
    rng = np.random.default_rng(seed)
    base = {"T1": t1, "T2": t2, "T_amb": amb}
    n = len(t)
    readings = np.empty((n, tables.n_temps))
    for r, name in enumerate(tables.raw_names):
        readings[:, r] = base[name] if name in base else rng.uniform(-150.0, 1150.0, n)
    faulty = readings.copy()
    p = tables.position_reading
    faulty[5:7, p] = np.nan
    faulty[20:25, p] = np.inf
    faulty[30, 0] = np.nan
    still = readings.copy()
    still[:, p] = 250.0
    streams_ = {"moving": readings, "faults": faulty, "still": still}
    if tables.has_dead_band:  # in and out of the band: every sensor near the reference, then not, then again
        band = readings.copy()
        ref = tables.dead_band_reading
        band[:, 1] = band[:, 0] + np.where((np.arange(n) % 16) < 8, 0.4, 3.0)
        band[:, ref] = band[:, 0] - 0.5
        streams_["dead band"] = band
    return streams_


def test_replay_is_the_offline_model_and_a_position_outside_the_travel_is_clamped_and_flagged():
    model = model_for(2, p=1)
    loaded = ModelFile.from_dict(model)
    readings = streams(model)["moving"]
    replay = SwitchingRule(model).replay(readings)
    inputs = readings[:, :2] - 0.0
    offline = loaded.predict_position(inputs, readings[:, 2], replay.group - 1, transfer=True)  # bumpless
    assert np.allclose(replay.prediction_um, offline, rtol=0, atol=1e-9)
    outside = (readings[:, 2] < 0) | (readings[:, 2] > 1000)
    assert outside.any()
    assert np.array_equal((replay.fault & FAULT_POSITION) > 0, outside)
    at_end = np.clip(readings[:, 2], 0, 1000)
    inside_end = loaded.predict_position(inputs, at_end, replay.group - 1, transfer=True)[outside]
    assert np.allclose(replay.prediction_um[outside], inside_end, atol=1e-9)


def test_a_missing_position_reading_is_held_then_a_sensor_fault():
    model = model_for(1, p=1)
    replay = SwitchingRule(model).replay(streams(model)["faults"])
    assert replay.fault[20] & FAULT_SENSOR == 0  # held for up to hold_samples
    assert np.any(replay.fault[20:25] & FAULT_SENSOR)


CASES = [(1, 1, False), (3, 1, True), (2, 0, True)]
ST_CASES = [pytest.param(case, marks=() if case == CASES[1] else pytest.mark.slow) for case in CASES]
"""The cases of the Structured Text evaluator (a block takes seconds to parse): the fast lane keeps the richest."""


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("single", [False, True])
def test_c_build_makes_the_decisions_of_replay_bit_for_bit(drivers, case, single):
    model = model_for(*case)
    chosen = streams(model)
    outputs = run_driver(drivers(case, model, "single" if single else "double"), list(chosen.values()))
    for temps, c_out in zip(chosen.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps, "single" if single else "double"))


@pytest.mark.parametrize("case", ST_CASES)
@pytest.mark.toolchain
def test_lreal_block_matches_replay(case):
    from support.structured_text import assert_lreal_block_replays

    model = model_for(*case)
    assert_lreal_block_replays(model, streams(model).values())


@pytest.mark.parametrize("case", ST_CASES)
def test_real_block_matches_the_single_precision_c_build_bit_for_bit(drivers, case):
    from support.structured_text import as_single, assert_same_decisions, run_block

    model = model_for(*case)
    (text,) = render(model, "st", real="REAL").values()
    chosen = as_single(list(streams(model).values()))
    st_out = run_block(text, chosen, model["sampling_period_s"], "REAL")
    c_out = run_driver(drivers(case, model, "single"), chosen)
    assert_same_decisions(st_out, c_out)


@pytest.mark.parametrize("case", CASES)
def test_the_json_table_is_format_4_and_enough_to_rebuild_the_rule(case):
    model = model_for(*case)
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    assert table["format"] == ("groupfit-runtime/7" if table.get("blend_samples") else "groupfit-runtime/4")
    assert table["fault_bits"]["position"] == FAULT_POSITION and table["position"]["order"] == case[0]
    for temps in streams(model).values():
        py = python_replay(model, temps)["compensation_um"]
        assert compensation(table, temps).tobytes() == py.tobytes()
        rule = SwitchingRule(model)
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected  # the position fault bit and the prediction too


def test_the_controller_sheet_fills_sd43900_to_43920_from_k0_tanb_and_p0():
    model = model_for(1, p=1)
    sheet = json.loads(render(model, "sheet")["groupfit_sheet.json"])
    sin = sheet["sinumerik"]
    assert sin["MD32750_TEMP_COMP_TYPE"] == 3
    assert sin["SD43920_TEMP_COMP_REF_POSITION"]["value"] == P0
    assert sin["SD43900_TEMP_COMP_ABS_VALUE"]["value"] == "-K0Um / 1000"
    assert sin["SD43910_TEMP_COMP_SLOPE"]["value"] == "-SlopeUmPerMm / 1000"
    text = render(model, "sheet")["groupfit_sheet.txt"]
    assert "SD43920 TEMP_COMP_REF_POSITION  = 500" in text and "clamped to the travel" in text


def test_k0_and_tanb_outputs_give_the_sinumerik_total():
    """SINUMERIK's dK = K0 + tanb (P - P0) from the rule's K0 and slope is its compensation inside the travel."""
    from groupfit.export.sheet import sinumerik_total_um

    model = model_for(1, p=1)
    rule = SwitchingRule(model)
    tables = rule.tables
    for row in streams(model)["moving"][:20]:
        result = rule.step(row)
        position = row[tables.position_reading]
        if not 0 <= position <= 1000:
            continue
        total = sinumerik_total_um(-float(rule.k0) / 1000, -float(rule.slope) / 1000, position, P0)
        assert total == pytest.approx(-result.prediction_um, abs=1e-9)


# --------------------------------------------------------------------- seed 001's rule


def seed_001_model() -> dict:
    """Seed 001: y = -(y1 - y2·l/1000), y1 and y2 linear in the rises; updated only while some |x_i - x_8| > 1 °C.

    Two sensors and the reference x8, round coefficients: y1 = 10·(x1 - x1^) - 4·(x2 - x2^) µm,
    y2 = 50·(x1 - x1^) µm per metre; l the position in mm, P0 = 0. The model's error is
    E = y1 - y2·l/1000, so K0 = y1 and tanb = -y2/1000 µm per mm; the compensation is -E = y.
    """
    return {
        "format": "groupfit-model/1",
        "sampling_period_s": 1200.0,
        "temps": ["x1", "x2"],
        "reference": "start",
        "error": "error_um",
        "intercept": True,
        "objective": "sse",
        "p": 0,
        "n": 0,
        "c": 1.0,
        "n_samples": 10,
        "breaks": [],
        "soft_groups": [[1, 10]],
        "coefficients": [[0.0, 10.0, -4.0]],
        "objective_value": 0.0,
        "switching": {
            "criterion": "x1",
            "criterion_index": 0,
            "criterion_series": [0.0] * 10,
            "rule": "groupfit-switch/1",
            "windows": [],
            "thresholds_c": [],
            "directions": [],
            "noise_c": 0.05,
            "margin_c": 0.15,
            "hold_samples": 1,
            "temp_min_c": [0.0, 0.0],
            "temp_max_c": [100.0, 100.0],
            "comp_min_um": -1000.0,
            "comp_max_um": 1000.0,
            "rate_limit_um": 1000.0,
            "period_tolerance": 0.01,
            "source_ranges": {"x8": [0.0, 100.0]},
        },
        "position": {
            "column": "l_mm",
            "p0_mm": 0.0,
            "order": 1,
            "travel_mm": [0.0, 600.0],
            "coefficients": [[[0.0, -50.0 / 1000.0, 0.0]]],
        },
        "dead_band": {"reference": "x8", "threshold_c": 1.0},
    }


def test_seed_001_rule_dead_band_sign_and_units_on_a_hand_made_case():
    model = seed_001_model()
    assert model_file_problem(model) is None
    rule = SwitchingRule(model)
    assert rule.tables.raw_names == ("x1", "x2", "x8", "l_mm")
    #              x1     x2     x8    l (mm)
    rows = [
        (20.0, 20.0, 20.0, 100.0),  # cold: the start reference; |x_i - x8| = 0: dead band, y = 0
        (20.8, 20.5, 20.0, 300.0),  # still within 1 °C of x8: no update, y = 0
        (22.0, 20.5, 20.0, 300.0),  # x1 - x8 = 2 > 1: y = -(y1 - y2 l/1000)
        (22.0, 21.0, 21.5, 500.0),  # every |x_i - x8| <= 1: no update, y as before
        (23.0, 21.0, 20.0, 0.0),  # outside again, at l = 0: y = -y1
    ]
    out = [rule.step(r) for r in rows]

    def y(x1, x2, l_mm):
        y1 = 10.0 * (x1 - 20.0) - 4.0 * (x2 - 20.0)
        y2 = 50.0 * (x1 - 20.0)
        return -(y1 - y2 * l_mm / 1000.0)

    expected = [0.0, 0.0, y(22.0, 20.5, 300.0), y(22.0, 20.5, 300.0), y(23.0, 21.0, 0.0)]
    assert [r.compensation_um for r in out] == pytest.approx(expected, abs=1e-12)
    assert expected[2] == pytest.approx(-(20.0 - 2.0 - 100.0 * 300.0 / 1000.0))  # = +12 µm, in µm
    # the prediction itself is not held: it is the model's error at every sample
    assert out[3].prediction_um == pytest.approx(-y(22.0, 21.0, 500.0))
    sheet = json.loads(render(model, "sheet")["groupfit_sheet.json"])
    assert sheet["dead_band"]["reference"] == "x8" and sheet["dead_band"]["threshold_c"] == 1.0


# --------------------------------------------------------------------- tables


@pytest.mark.parametrize("tolerance", [0.5, 0.1])
def test_an_interpolated_table_reproduces_the_model_within_its_tolerance(tolerance):
    model, run = fitted(3, p=0)
    states = position_coefficients(model, run.run.temps, np.zeros(run.run.n_samples, dtype=int))
    table = position_table(model, states, tolerance_um=tolerance)
    assert table.error_um <= tolerance
    assert np.isclose(table.spacing_mm * (len(table.nodes_mm) - 1), 1000.0)
    rng = np.random.default_rng(7)
    positions = rng.uniform(0.0, 1000.0, 10_000)
    rows = rng.integers(0, run.run.n_samples, 10_000)
    inputs = run.run.temps[rows]
    exact = model.predict_position(inputs, positions, np.zeros(10_000, dtype=int))
    k0 = model.predict(inputs, np.zeros(10_000, dtype=int))
    interpolated = k0 + np.sum(states[rows] * table.interpolate(positions), axis=1)
    assert np.max(np.abs(interpolated - exact)) <= tolerance
    assert table_error(model, table, states, positions) <= tolerance


def test_a_table_of_a_linear_model_needs_two_nodes_and_is_exact():
    model, run = fitted(1)
    states = position_coefficients(model, run.run.temps, np.zeros(run.run.n_samples, dtype=int))
    table = position_table(model, states)
    assert len(table.nodes_mm) == 2 and table.error_um < 1e-9


# --------------------------------------------------------------------- the command line


def test_fit_position_writes_a_position_model_and_export_writes_its_table(tmp_path, capsys):
    long_table(3).to_csv(tmp_path / "axis.csv", index=False)
    out = tmp_path / "fit"
    code = main(
        ["fit", "--data", str(tmp_path / "axis.csv"), "--temps", "T1,T2", "--reference", "none", "--p", "0"]
        + ["--position", "P_mm", "--position-order", "auto", "--position-ref", "500", "--out", str(out), "--quiet"]
    )
    assert code == 0
    model = ModelFile.load(out / "model.json")
    assert model.position.order == 3 and model.position.p0_mm == 500.0
    assert model.position.travel_mm == (0.0, 1000.0)
    code = main(["export", str(out / "model.json"), "--target", "table", "--out", str(tmp_path / "table")])
    assert code == 0
    text = (tmp_path / "table" / "groupfit_position_table.csv").read_text()
    assert "interpolation error" in text
    assert (tmp_path / "table" / "groupfit_position_table.h").is_file()


def test_fit_position_without_temps_takes_the_temperature_columns_by_name(tmp_path, capsys):
    """The README's example names no --temps: the inputs are the table's temperature columns, as without
    --position, and the model is the one --temps names them in."""
    long_table(3).to_csv(tmp_path / "axis.csv", index=False)
    common = ["fit", "--data", str(tmp_path / "axis.csv"), "--position", "P_mm", "--reference", "none", "--quiet"]
    assert main([*common, "--out", str(tmp_path / "default")]) == 0
    assert main([*common, "--temps", "T1,T2", "--out", str(tmp_path / "named")]) == 0
    default = ModelFile.load(tmp_path / "default" / "model.json")
    named = ModelFile.load(tmp_path / "named" / "model.json")
    assert list(default.temps) == list(named.temps) == ["T1", "T2"]
    np.testing.assert_array_equal(default.coefficients, named.coefficients)


def test_fit_refuses_a_missing_position_column(tmp_path, capsys):
    long_table(1).to_csv(tmp_path / "axis.csv", index=False)
    code = main(
        ["fit", "--data", str(tmp_path / "axis.csv"), "--temps", "T1,T2", "--position", "Y_mm", "--out", str(tmp_path)]
    )
    assert code != 0
    assert "position column 'Y_mm' not found" in capsys.readouterr().err


def test_position_order_needs_position(tmp_path, capsys):
    long_table(1).to_csv(tmp_path / "axis.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "axis.csv"), "--temps", "T1,T2", "--position-order", "2"]
    code = main([*args, "--out", str(tmp_path)])
    assert code != 0
    assert "--position-order needs --position" in capsys.readouterr().err


def test_replay_reads_the_position_column(tmp_path, capsys):
    model = model_for(1, p=1)
    (tmp_path / "model.json").write_text(json.dumps(model))
    readings = streams(model)["moving"]
    frame = pd.DataFrame(readings, columns=RuleTables.from_model(model).raw_names)
    frame.insert(0, "time_s", np.arange(len(frame)) * 1200.0)
    frame.to_csv(tmp_path / "live.csv", index=False)
    code = main(
        [
            "replay",
            str(tmp_path / "model.json"),
            "--data",
            str(tmp_path / "live.csv"),
            "--json",
            str(tmp_path / "r.json"),
        ]
    )
    assert code == 0
    result = json.loads((tmp_path / "r.json").read_text())
    outside = (readings[:, -1] < 0) | (readings[:, -1] > 1000)
    assert result["faults"]["position_clamped_samples"] == int(outside.sum())
    compensation = [s["compensation_um"] for s in result["samples"]]
    assert compensation == python_replay(model, readings)["compensation_um"].tolist()
    frame.drop(columns=["P_mm"]).to_csv(tmp_path / "blind.csv", index=False)
    code = main(["replay", str(tmp_path / "model.json"), "--data", str(tmp_path / "blind.csv")])
    assert code != 0
    assert (
        "column 'P_mm' not found; the model reads it (axis position (mm) of the position terms)"
        in capsys.readouterr().err
    )


def test_the_position_is_the_last_reading_and_an_order_above_the_positions_is_refused():
    tables = RuleTables.from_model(model_for(1))
    assert tables.has_position and tables.raw_names[-1] == "P_mm"
    with pytest.raises(InputError):
        with_position(
            ModelFile.from_dict(model_for(1)), load_position_run(long_table(1), "P_mm", temps=["T1", "T2"]), 11, P0
        )


# --------------------------------------------------------------------- with derived inputs, hostile readings


def derived_position_model() -> tuple[dict, dict[str, np.ndarray]]:
    """A model with derived inputs given position terms of order 2 and a dead band (coefficients made up)."""
    from test_switching_models import augmented_model, derived_streams

    model, run = augmented_model("all kinds p=2")
    width = len(model["temps"]) + int(model["intercept"])
    rng = np.random.default_rng(11)
    rows = [[list(rng.normal(0, 1e-2, width)), list(rng.normal(0, 1e-5, width))] for _ in model["coefficients"]]
    plain = derived_streams(model, run)
    position = {"column": "X_mm", "p0_mm": 100.0, "order": 2, "travel_mm": [-50.0, 400.0], "coefficients": rows}
    model["position"] = position
    model["dead_band"] = {"reference": model["temps"][0], "threshold_c": 0.5}
    assert model_file_problem(model) is None
    assert RuleTables.from_model(model).raw_names[-1] == "X_mm"
    chosen = {}
    for label, raw in plain.items():
        chosen[label] = np.column_stack([raw, rng.uniform(-200.0, 550.0, len(raw))])
    hostile = chosen["faults"].copy()
    specials = [np.nan, np.inf, -np.inf, 1e308, -1e308, 5e-324, -0.0, 3.4e38, 1e39, 1e9, -1e9]
    hostile[: len(specials), -1] = specials
    chosen["hostile position"] = hostile
    return model, chosen


@pytest.mark.parametrize("single", [False, True])
@pytest.mark.toolchain
def test_derived_inputs_with_position_and_dead_band_c_build_is_the_python_rule(tmp_path, single):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    model, chosen = derived_position_model()
    write(render(model, "c"), tmp_path)
    flags = ("-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all")
    driver = build_driver(tmp_path, tmp_path / "driver", single=single, flags=flags)
    outputs = run_driver(driver, list(chosen.values()))
    for temps, c_out in zip(chosen.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps, "single" if single else "double"))
        assert np.all(np.isfinite(c_out.compensation_um))


@pytest.mark.toolchain
@pytest.mark.slow
def test_derived_inputs_with_position_and_dead_band_lreal_block_is_the_python_rule():
    from support.structured_text import run_block

    model, chosen = derived_position_model()
    (text,) = render(model, "st", real="LREAL").values()
    streams_ = {k: chosen[k] for k in ("modelling", "source faults", "hostile position")}
    outputs = run_block(text, list(streams_.values()), model["sampling_period_s"], "LREAL")
    for temps, out in zip(streams_.values(), outputs):
        py = python_replay(model, temps)
        assert out["fault"].tolist() == py["fault"].tolist()
        assert out["compensation_um"].tobytes() == py["compensation_um"].tobytes()


def test_derived_inputs_with_position_and_dead_band_json_table_is_enough_to_rebuild_the_rule():
    model, chosen = derived_position_model()
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    assert table["format"] == "groupfit-runtime/7" and table["derived_inputs"] and table["dead_band"]
    for temps in chosen.values():
        rule = SwitchingRule(model)
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected


@pytest.mark.parametrize("real", ["REAL", "LREAL"])
@pytest.mark.toolchain
@pytest.mark.slow
def test_the_position_block_and_the_table_parse_as_structured_text(real):
    from support.structured_text import blark_accepts, tree_sitter_errors

    model = model_for(3, p=1, dead_band=True)
    texts = [render(model, "st", real=real)["FB_GroupfitComp.st"]]
    texts += [text for name, text in render(model, "table", real=real).items() if name.endswith(".st")]
    for text in texts:
        assert not tree_sitter_errors(text) and blark_accepts(text)
        assert text.isascii()


@pytest.mark.parametrize(
    "options, message",
    [
        (["--position", "error_um"], "--position 'error_um' is the run's thermal error"),
        (["--position", "time_s"], "--position 'time_s' is the run's time"),
        (
            ["--position", "P_mm", "--dead-band", "0.5", "--dead-band-ref", "P_mm"],
            "the axis position, not a temperature",
        ),
    ],
)
def test_the_position_column_is_no_other_role_of_the_run(tmp_path, capsys, options, message):
    """Before: 'column error_um not found' (it was there) and '--dead-band-ref P_mm: no such column'."""
    long_table(1).to_csv(tmp_path / "run.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "run.csv"), "--temps", "T1,T2", "--p", "0", *options]
    assert main([*args, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "o").exists()
