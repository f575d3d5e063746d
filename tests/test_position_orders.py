"""The position fit's per-order residual table (seed 004) and its figure of error against position."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from test_position import P0, long_table

from groupfit.cli import main
from groupfit.models import GroupedRegressor
from groupfit.position import load_position_run, residual_by_order


def global_model(order_truth: int, noise: float):
    prun = load_position_run(long_table(order_truth, noise), "P_mm", temps=["T1", "T2"])
    model = GroupedRegressor(p=0, search="exact").fit(prun.run.temps, prun.run.error).to_model_file(prun.run)
    return model, prun


def test_a_noise_free_cubic_leaves_no_residual_from_order_3_on():
    model, prun = global_model(3, noise=0.0)
    table = {row["order"]: row for row in residual_by_order(model, prun, P0)}
    assert sorted(table) == [1, 2, 3, 4, 5]
    assert table[1]["max_um"] > 1.0 and table[2]["max_um"] > 1.0
    assert all(table[k]["max_um"] < 1e-8 for k in (3, 4, 5))


def test_each_order_is_the_least_squares_fit_of_scikit_learn():
    model, prun = global_model(2, noise=0.1)
    d = prun.position - P0
    inputs = prun.inputs()
    for row in residual_by_order(model, prun, P0):
        k = row["order"]
        features = np.column_stack([d**j for j in range(1, k + 1)] + [inputs * (d**j)[:, None] for j in range(k + 1)])
        features = features / features.std(axis=0)  # the powers of d span 13 decades: scaled for the solver
        residual = prun.error - LinearRegression().fit(features, prun.error).predict(features)
        assert row["max_um"] == pytest.approx(np.max(np.abs(residual)), abs=1e-7)
        assert row["mean_um"] == pytest.approx(np.mean(np.abs(residual)), abs=1e-8)


def test_orders_above_the_positions_are_left_out():
    prun = load_position_run(long_table(1, 0.1, positions=np.array([0.0, 400.0, 1000.0])), "P_mm", temps=["T1"])
    model = GroupedRegressor(p=0, search="exact").fit(prun.run.temps, prun.run.error).to_model_file(prun.run)
    assert [row["order"] for row in residual_by_order(model, prun, P0)] == [1, 2]


def test_fit_prints_the_table_writes_it_in_json_and_draws_error_against_position(tmp_path, capsys):
    long_table(3).to_csv(tmp_path / "axis.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "axis.csv"), "--temps", "T1,T2", "--position", "P_mm"]
    args += ["--position-order", "4", "--p", "0", "--out", str(tmp_path / "m"), "--json", str(tmp_path / "r.json")]
    assert main([*args, "--quiet"]) == 0
    out = capsys.readouterr().out
    orders = json.loads((tmp_path / "r.json").read_text())["training"]["position_orders"]
    assert [row["order"] for row in orders] == [1, 2, 3, 4, 5]
    line = next(text for text in out.splitlines() if text.startswith("residual by order"))
    assert f"4: {orders[3]['max_um']:.3g} / {orders[3]['mean_um']:.3g}" in line
    assert (tmp_path / "m" / "position.png").stat().st_size > 0
