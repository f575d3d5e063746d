"""Units given with a factor or in another spelling in a column's name are read in that unit.

A gauge's ``dZ [1/1000 mm]`` is micrometres, a PLC's ``T1 [0.1°C]`` tenths of a degree; ``T1 (F)`` and
``T1 [ºF]`` (the ordinal sign for the degree) are Fahrenheit and ``T1 (°K)`` kelvin. The same numbers in such a
log must give the same model as the plain log.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.default_columns import length_unit, named_length_unit
from groupfit.switching_checks import switch_direction
from groupfit.unit_factors import factored_unit
from groupfit.units_row import named_temperature_unit

PAPER_CYCLE = SYNTHETIC.parent / "paper_cycle.csv"


@pytest.mark.parametrize(
    "name, factor, unit",
    [
        ("dZ [1/1000 mm]", 1e-3, "mm"),
        ("dZ [0.001 mm]", 1e-3, "mm"),
        ("dZ [0,1 µm]", 0.1, "µm"),
        ("dZ [µm/10]", 0.1, "µm"),
        ("err (10 nm)", 10.0, "nm"),
        ("T1 [°C/10]", 0.1, "°C"),
        ("T1 [°C*0.1]", 0.1, "°C"),
    ],
)
def test_a_factor_in_the_unit_is_read(name, factor, unit):
    found = factored_unit(name)
    assert found is not None and found.factor == pytest.approx(factor) and found.unit == unit


@pytest.mark.parametrize("name", ["Drehzahl [1/min]", "T1 [°C]", "dZ [mm]", "probe (1)", "q [W/m2]", "v [m/s]"])
def test_a_unit_without_a_factor_or_a_rate_is_not_a_factored_unit(name):
    assert factored_unit(name) is None


def test_the_length_of_a_factored_unit_is_the_factor_times_the_unit():
    assert length_unit("dZ [1/1000 mm]")[1] == pytest.approx(1.0)
    assert length_unit("dZ [0.1 µm]")[1] == pytest.approx(0.1)
    assert length_unit("dZ [mm]")[1] == 1000.0
    assert named_length_unit("dZ [1/1000 mm]") is None  # not "mm": the bare unit would read it ×1000


@pytest.mark.parametrize(
    "name, unit", [("T1 (F)", "f"), ("T1 [ºF]", "ºf"), ("T1 (deg. F)", "deg.f"), ("T1 (°K)", "°k"), ("T1", None)]
)
def test_spellings_of_fahrenheit_and_kelvin_are_units(name, unit):
    assert named_temperature_unit(name) == unit


def _fit(tmp_path, frame: pd.DataFrame, stem: str, *options) -> dict:
    path, report = tmp_path / f"{stem}.csv", tmp_path / f"{stem}.json"
    frame.to_csv(path, index=False)
    argv = ["fit", "--data", str(path), "--quiet", "--json", str(report), "--out", str(tmp_path / stem)]
    assert main([*argv, *(options if "--p" in options else ("--p", "0", *options))]) == 0
    return json.loads(report.read_text())


@pytest.fixture(scope="module")
def plain():
    return pd.read_csv(PAPER_CYCLE)[["time_s", "T1", "T2", "T_amb", "error_um"]]


@pytest.mark.parametrize(
    "column, logged",
    [
        ("dZ [1/1000 mm]", lambda e: e),
        ("dZ [0.1 µm]", lambda e: e * 10.0),
        ("dZ [µm/10]", lambda e: e * 10.0),
        ("dZ [10 nm]", lambda e: e * 100.0),
        ("dZ [in]", lambda e: e / 25400.0),
        ("dZ [mils]", lambda e: e / 25.4),
        ("dZ_thou", lambda e: e / 25.4),
        ("dZ [0.0001 in]", lambda e: e / 2.54),
    ],
)
def test_an_error_in_a_factored_unit_gives_the_plain_model(tmp_path, plain, capsys, column, logged):
    reference = _fit(tmp_path, plain, "plain", "--temps", "T1,T2")
    frame = plain.assign(**{column: logged(plain["error_um"])}).drop(columns="error_um")
    factored = _fit(tmp_path, frame, "factored", "--temps", "T1,T2", "--error", column)
    assert np.allclose(factored["coefficients"], reference["coefficients"], rtol=1e-9, atol=1e-9)
    assert f"column '{column}' is in" in capsys.readouterr().out


@pytest.mark.parametrize(
    "template, logged",
    [
        ("{} [0.1°C]", lambda t: t * 10.0),
        ("{} [°C/10]", lambda t: t * 10.0),
        ("{} (F)", lambda t: t * 9.0 / 5.0 + 32.0),
        ("{} [ºF]", lambda t: t * 9.0 / 5.0 + 32.0),
        ("{} (deg. F)", lambda t: t * 9.0 / 5.0 + 32.0),
        ("{} (°K)", lambda t: t + 273.15),
    ],
)
def test_temperatures_in_a_factored_unit_or_another_spelling_give_the_plain_model(tmp_path, plain, template, logged):
    reference = _fit(tmp_path, plain, "plain", "--temps", "T1,T2")
    renamed = {c: template.format(c) for c in ("T1", "T2", "T_amb")}
    frame = plain.assign(**{renamed[c]: logged(plain[c]) for c in renamed}).drop(columns=list(renamed))
    temps = ",".join(renamed[c] for c in ("T1", "T2"))
    converted = _fit(tmp_path, frame, "converted", "--temps", temps, "--ambient", renamed["T_amb"])
    assert np.allclose(converted["coefficients"], reference["coefficients"], rtol=1e-6, atol=1e-6)
    span = converted["training"]["input_span"][renamed["T1"]]
    assert span == pytest.approx(reference["training"]["input_span"]["T1"], abs=1e-6)


def test_a_position_column_in_metres_is_read_in_mm_by_fit_and_replay(tmp_path, capsys):
    """``probe_x_m`` holds metres: the model, its travel and its replay are those of the same run in mm."""
    metres = pd.read_csv(SYNTHETIC.parent / "screw_nut.csv")
    millimetres = metres.assign(probe_x_mm=metres["probe_x_m"] * 1000.0).drop(columns="probe_x_m")
    temps = ["--temps", "T0mm,T40mm,T80mm,T120mm", "--reference", "start"]
    fits, replays = [], []
    for column, frame in (("probe_x_m", metres), ("probe_x_mm", millimetres)):
        fits.append(_fit(tmp_path, frame, column, *temps, "--position", column)["position"])
        report = tmp_path / f"{column}_replay.json"
        model = tmp_path / column / "model.json"
        assert main(["replay", str(model), "--data", str(tmp_path / f"{column}.csv"), "--json", str(report)]) == 0
        replays.append(json.loads(report.read_text())["rms_um"])
    assert fits[0]["p0_mm"] == fits[1]["p0_mm"] == pytest.approx(150.0)
    assert fits[0]["travel_mm"] == fits[1]["travel_mm"]
    assert np.allclose(np.asarray(fits[0]["coefficients"], float), np.asarray(fits[1]["coefficients"], float))
    assert replays[0] == pytest.approx(replays[1], rel=1e-12) and replays[0] < 0.2
    assert "position column 'probe_x_m' is in another unit than mm by its name: read ×1000" in capsys.readouterr().out


def test_a_change_at_the_margin_gives_one_direction_whatever_the_rounding():
    margin = 3 * 0.05
    assert switch_direction(0.14999999999999858, margin) == switch_direction(0.15000000000000568, margin) == 0
    assert switch_direction(0.1501, margin) == 1 and switch_direction(-0.1501, margin) == -1


def test_a_run_logged_in_fahrenheit_gives_the_rule_of_the_run_in_celsius(tmp_path, plain):
    """Readings of 0.01 °C make changes of exactly 3 × 0.05 °C common; in °F they differ in the last bits."""
    fahrenheit = plain.assign(**{c: (plain[c] * 9.0 / 5.0 + 32.0).round(3) for c in ("T1", "T2", "T_amb")})
    fahrenheit = fahrenheit.rename(columns={c: f"{c} [°F]" for c in ("T1", "T2", "T_amb")})
    options = ("--p", "2", "--search", "exact", "--recalibrate", "none")
    celsius = _fit(tmp_path, plain, "celsius", "--temps", "T1,T2", *options)
    converted = _fit(tmp_path, fahrenheit, "fahrenheit", "--temps", "T1 [°F],T2 [°F]", *options)
    assert converted["breaks"] == celsius["breaks"]
    assert converted["switching"]["directions"] == celsius["switching"]["directions"]


def test_the_export_of_a_model_of_a_fahrenheit_log_says_to_pass_degrees_celsius(tmp_path, plain):
    fahrenheit = plain.assign(**{c: plain[c] * 9.0 / 5.0 + 32.0 for c in ("T1", "T2", "T_amb")})
    fahrenheit = fahrenheit.rename(columns={c: f"{c} (F)" for c in ("T1", "T2", "T_amb")})
    _fit(tmp_path, fahrenheit, "fahrenheit", "--temps", "T1 (F),T2 (F)", "--recalibrate", "none")
    out = tmp_path / "export"
    assert main(["export", str(tmp_path / "fahrenheit" / "model.json"), "--target", "all", "--out", str(out)]) == 0
    sheet = (out / "groupfit_sheet.txt").read_text()
    assert sheet.count("logged in degF: pass it in degC") == 3  # both inputs and the reference
    assert "T_amb (F)" in sheet and "valid 9 .. 31 degC" in sheet
    header = (out / "groupfit_model.h").read_text()
    assert header.count("logged in degF: pass it in degC") == 3
    scale, offset = re.search(r"degC = x \* (\S+) - (\S+), as groupfit converts it", header).groups()
    readings = fahrenheit["T1 (F)"].to_numpy()  # the note's formula is the reader's, bit for bit
    loaded = load_run(tmp_path / "fahrenheit.csv", temps=["T1 (F)", "T2 (F)"], error="error_um")
    assert (readings * float(scale) - float(offset)).tobytes() == loaded.temps[:, 0].tobytes()
