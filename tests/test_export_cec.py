"""``export --target cec``: the SINUMERIK compensation table read back by a parser of its own and interpolated."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from test_position import fitted, long_table

from groupfit.cli import main

ASSIGNMENT = re.compile(r"^\$(AN_CEC(?:_[A-Z_]+)?)\[(\d+)(?:,(\d+))?\]=(.+)$")


def parse_cec(text: str) -> dict:
    """The tables of a ``%_N_NC_CEC_INI`` file: per table index its values (by point) and parameters."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    assert lines[0] == "%_N_NC_CEC_INI" and lines[1] == "CHANDATA(1)" and lines[-1] == "M17"
    tables: dict[int, dict] = {}
    for line in lines[2:-1]:
        if line.startswith(";"):
            continue
        match = ASSIGNMENT.match(line)
        assert match, f"not a CEC assignment: {line!r}"
        name, t, n, value = match.groups()
        table = tables.setdefault(int(t), {"values": {}})
        if name == "AN_CEC":
            table["values"][int(n)] = float(value)
        elif name in ("AN_CEC_INPUT_AXIS", "AN_CEC_OUTPUT_AXIS"):
            assert value.startswith("(") and value.endswith(")")
            table[name] = value[1:-1]
        else:
            table[name] = float(value)
    for table in tables.values():
        points = round((table["AN_CEC_MAX"] - table["AN_CEC_MIN"]) / table["AN_CEC_STEP"]) + 1
        assert sorted(table["values"]) == list(range(points))
        table["nodes"] = table["AN_CEC_MIN"] + table["AN_CEC_STEP"] * np.arange(points)
        table["array"] = np.array([table["values"][n] for n in range(points)])
    return tables


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    model, prun = fitted(order=3, p=0)
    path = tmp_path_factory.mktemp("cec") / "model.json"
    path.write_text(json.dumps(model.to_dict()))
    return path, model, prun


def export(model_path, out, *options) -> int:
    return main(["export", str(model_path), "--target", "cec", "--out", str(out), *map(str, options)])


@pytest.mark.parametrize("tolerance", [0.5, 0.1])
def test_the_table_interpolates_the_model_within_its_tolerance(tmp_path, model_file, tolerance):
    path, model, prun = model_file
    state = prun.run.temps[30]
    assert (
        export(path, tmp_path, "--state", f"T1={float(state[0])!r},T2={float(state[1])!r}", "--tolerance-um", tolerance)
        == 0
    )
    text = (tmp_path / "NC_CEC.INI").read_text()
    table = parse_cec(text)[0]
    low, high = model.position.travel_mm
    assert table["AN_CEC_MIN"] == low and table["AN_CEC_MAX"] >= high
    assert table["AN_CEC_INPUT_AXIS"] == table["AN_CEC_OUTPUT_AXIS"] == "AX1"
    positions = np.random.default_rng(0).uniform(low, high, 10_000)
    truth = model.predict_position(np.repeat(state[None, :], len(positions), axis=0), positions, np.zeros(10_000, int))
    applied = np.interp(positions, table["nodes"], table["array"])  # mm, added to the axis
    error = np.max(np.abs(-1000.0 * applied - truth))
    stated = float(re.search(r"interpolation error ([0-9.e+-]+) um", text).group(1))
    assert error <= tolerance and error <= stated * 1.001 + 1e-9
    assert abs(truth).max() > 20 * tolerance  # the model is far from flat: the table carries it


def test_a_given_step_table_number_and_axes_are_written(tmp_path, model_file):
    path, model, prun = model_file
    args = ["--state", "T1=25,T2=23", "--step", "12.5", "--table", "3", "--base-axis", "X1", "--comp-axis", "Z1"]
    assert export(path, tmp_path, *args) == 0
    table = parse_cec((tmp_path / "NC_CEC.INI").read_text())[3]
    assert table["AN_CEC_STEP"] == 12.5 and len(table["array"]) == 81
    assert (table["AN_CEC_INPUT_AXIS"], table["AN_CEC_OUTPUT_AXIS"]) == ("X1", "Z1")
    at_min = model.predict_position(np.array([[25.0, 23.0]]), np.array([0.0]), np.zeros(1, int))[0]
    assert table["array"][0] == round(-at_min / 1000.0, 6)  # the compensation is minus the error, in mm


@pytest.mark.parametrize(
    "options, message",
    [
        (["--state", "T1=25,T2=23", "--step", "0.4"], "needs 2501 points, the controller takes at most 2000"),
        (["--state", "T1=25,T2=23", "--tolerance-um", "0.001", "--max-points", "30"], "no table of at most 30"),
        ([], "give it with --state T1=VALUE,T2=VALUE"),
        (["--state", "T1=25"], "no value for the model input(s) T2"),
        (["--state", "T1=25,T2=23", "--base-axis", "x 1"], "--base-axis 'x 1'"),
        (["--state", "T1=25,T2=23", "--step", "1e-6"], "needs 1000000001 points, the controller takes at most"),
        (["--state", "T1=25,T2=23", "--step", "1e9"], "longer than the travel 0 .. 1000 mm"),
        (["--state", "T1=25,T2=23,T1=24"], "--state: names 'T1' twice"),
        (["--state", "T1=1e308,T2=23"], "a thermal state's inputs lie within ±1e+06"),
        (["--state", "T1=nan,T2=23"], "a thermal state's inputs lie within"),
    ],
)
def test_bad_requests_are_refused_with_one_line_and_nothing_written(tmp_path, model_file, capsys, options, message):
    path = model_file[0]
    assert export(path, tmp_path / "out", *options) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not (tmp_path / "out").exists()


def test_a_model_with_breaks_is_refused(tmp_path, capsys):
    model, _ = fitted(order=1, p=1)
    (tmp_path / "m.json").write_text(json.dumps(model.to_dict()))
    assert export(tmp_path / "m.json", tmp_path / "out", "--state", "T1=25,T2=23") == 2
    assert "a table is one curve over the position" in capsys.readouterr().err


def with_training(path, tmp_path, **changes):
    """The model file of ``path`` with ``changes`` to its training and switching sections, written to tmp_path."""
    data = json.loads(path.read_text())
    data["training"] = {**(data.get("training") or {}), **changes.get("training", {})}
    data["switching"] = {**data["switching"], **changes.get("switching", {})}
    changed = tmp_path / "changed.json"
    changed.write_text(json.dumps(data))
    return changed


def test_a_state_far_outside_the_modelling_run_is_refused_and_one_near_it_is_written(tmp_path, model_file, capsys):
    path, model, prun = model_file
    frame = long_table(3)  # the modelling run, read here without the loader: its span of T1 and T2
    span = {name: [float(frame[name].min()), float(frame[name].max())] for name in ("T1", "T2")}
    changed = with_training(path, tmp_path, training={"input_span": span})
    (t1_low, t1_high), t2 = span["T1"], float(np.mean(span["T2"]))
    inside = t1_high + 0.2 * (t1_high - t1_low)
    assert export(changed, tmp_path / "near", "--state", f"T1={inside!r},T2={t2!r}") == 0
    outside = t1_high + 0.3 * (t1_high - t1_low)
    assert export(changed, tmp_path / "far", "--state", f"T1={outside!r},T2={t2!r}") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--state T1={outside:g}" in err[0] and f"spans {t1_low:.4g} .. {t1_high:.4g}" in err[0]
    assert not (tmp_path / "far").exists()


def test_a_table_beyond_the_rules_clamp_is_refused(tmp_path, model_file, capsys):
    path, model, prun = model_file
    state = prun.run.temps[30]
    low, high = model.position.travel_mm
    nodes = np.linspace(low, high, 1001)
    error = model.predict_position(np.repeat(state[None, :], 1001, axis=0), nodes, np.zeros(1001, int))
    largest = float(np.max(np.abs(error)))
    clamp = {"comp_min_um": -largest / 2, "comp_max_um": largest / 2}
    changed = with_training(path, tmp_path, switching=clamp)
    text = f"T1={float(state[0])!r},T2={float(state[1])!r}"
    assert export(path, tmp_path / "as_fitted", "--state", text) == 0  # within the model's own clamp
    assert export(changed, tmp_path / "clamped", "--state", text) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"beyond the model's clamp {-largest / 2:g} .. {largest / 2:g} um" in err[0]
    assert not (tmp_path / "clamped").exists()
