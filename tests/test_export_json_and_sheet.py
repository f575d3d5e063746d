"""JSON table, controller sheet and the ``groupfit export`` command."""

import json
import math

import pytest
from support import write_model
from support.json_runtime import run_table
from test_switching_models import augmented_model, derived_streams, streams_for, synthetic_model

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.export import render
from groupfit.export.json_table import STEPS
from groupfit.export.json_transfer import TRANSFER_STEP
from groupfit.export.sheet import (
    IntegerForm,
    controller_sheet,
    sinumerik_abs_value_mm,
    sinumerik_temp_comp_type,
    sinumerik_total_um,
)
from groupfit.runtime import RuleTables, SwitchingRule


def test_json_table_is_enough_to_rebuild_the_rule():
    model, run = synthetic_model()
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    # the bumpless transfer makes /6: a runtime for /1 … /5 refuses it instead of switching hard
    assert table["format"] == "groupfit-runtime/7" and table["temps"] == model["temps"]
    assert table["blend_samples"] == model["n"] and TRANSFER_STEP in table["steps"]
    rule = SwitchingRule(model)
    for temps in streams_for(model, run).values():
        rule.reset()
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected


@pytest.mark.parametrize("label", ["all kinds p=2", "on/off p=1"])
def test_json_table_with_derived_inputs_is_enough_to_rebuild_the_rule(label):
    model, run = augmented_model(label)
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    tables = RuleTables.from_model(model)
    assert table["format"] == "groupfit-runtime/7" and table["temps"] == list(tables.raw_names)
    assert [d["name"] for d in table["derived_inputs"]] == [d["name"] for d in model["derived_inputs"]]
    assert len(table["inputs"]) == len(model["temps"]) == len(table["coefficients"][0]) - 1
    rule = SwitchingRule(model)
    for temps in derived_streams(model, run).values():
        rule.reset()
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected


def test_json_table_with_a_power_stage_and_rest_start_is_format_3_and_enough_to_rebuild_the_rule():
    model, run = augmented_model("heat law p=2")
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    assert table["format"] == "groupfit-runtime/7"  # a runtime for /2 refuses it instead of computing wrongly
    table["steps"].remove(TRANSFER_STEP)
    first, identity, delay, steady = table["derived_inputs"]
    assert first["exponent"] == 5 / 3 and first["power_scale"] == 1000.0 and first["start"] == "rest"
    assert identity["start"] == "steady" and identity["exponent"] == 5 / 3
    assert delay["exponent"] is None and delay["power_scale"] is None and delay["start"] == "rest"
    assert steady["start"] == "steady" and steady["scale"] == 0.0  # 'scale' stays the derivative's factor
    assert "pow(abs(v) / power_scale, exponent)" in table["steps"][2] and "'rest'" in table["steps"][2]
    assert table["steps"][:2] == list(STEPS[:2]) and table["steps"][3:] == list(STEPS[3:])
    rule = SwitchingRule(model)
    for temps in derived_streams(model, run).values():
        rule.reset()
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected


def test_json_table_with_an_on_time_is_format_5_and_enough_to_rebuild_the_rule():
    model, run = augmented_model("on-time p=1")
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    assert table["format"] == "groupfit-runtime/7"  # a runtime for /4 refuses it instead of computing wrongly
    heat, speed = table["derived_inputs"]
    assert heat["transform"] == speed["transform"] == "ontime" and heat["start"] == "rest"
    assert heat["scale"] == model["sampling_period_s"] / 3600.0 and heat["exponent"] == 5 / 3
    assert "ontime: memory[k] = memory[k] + 1 if v != 0" in table["steps"][2]
    rule = SwitchingRule(model)
    for temps in derived_streams(model, run).values():
        rule.reset()
        expected = [(r.code, r.fault, r.prediction_um, r.compensation_um) for r in map(rule.step, temps)]
        assert run_table(table, temps) == expected
    # the heat law is formats /3 and /4 as before: only an on-time makes /5 (with a hard switch)
    hard = augmented_model("heat law p=2")[0]
    hard["switching"]["blend_samples"] = 0
    assert json.loads(render(hard, "json")["groupfit_runtime.json"])["format"] == "groupfit-runtime/3"
    hard = augmented_model("on-time p=1")[0]
    hard["switching"]["blend_samples"] = 0
    assert json.loads(render(hard, "json")["groupfit_runtime.json"])["format"] == "groupfit-runtime/5"


def test_models_without_power_or_rest_keep_their_json_format_and_steps():
    for label, fmt in [("all kinds p=2", "groupfit-runtime/2"), ("on/off p=1", "groupfit-runtime/2")]:
        model = augmented_model(label)[0]
        model["switching"]["blend_samples"] = 0  # a model file written before the transfer: a hard switch
        table = json.loads(render(model, "json")["groupfit_runtime.json"])
        assert table["format"] == fmt and table["steps"] == list(STEPS) and "blend_samples" not in table
        assert all("exponent" not in d and "start" not in d for d in table["derived_inputs"])


def test_sheet_describes_the_power_stage_and_the_start():
    model, _ = augmented_model("heat law p=2")
    text = render(model, "sheet")["groupfit_sheet.txt"]
    assert (
        "derived input (speed_rpm/1000)^1.667~lp1800sr: low-pass of (|speed_rpm| / 1000)^1.66667, tau = 1800 s, "
        "from rest, by the routine itself"
    ) in text
    assert "derived input (speed_rpm/1000)^1.667: (|speed_rpm| / 1000)^1.66667 (heat law)" in text
    assert " 5. speed_rpm        valid 0 .. 12000 " in text and text.isascii()


def test_sheet_lists_the_readings_the_controller_must_provide():
    model, _ = augmented_model("on/off p=1")
    sheet = controller_sheet(RuleTables.from_model(model))
    names = [r["name"] for r in sheet["readings"]]
    assert names == ["T1", "T2", "T3", "T4", "src_zscrew_on", "spindle_on"]
    on_off = sheet["readings"][4]
    assert on_off["valid_min"] == 0.0 and on_off["valid_max"] == 1.0 and on_off["unit"] != "degC"
    assert on_off["feeds"] == ["source of derived input src_zscrew_on~lp3600s"]
    assert sheet["readings"][0]["criterion"] and sheet["readings"][0]["unit"] == "degC"
    text = render(model, "sheet")["groupfit_sheet.txt"]
    assert "Readings the controller passes every sample, in this order" in text
    assert " 5. src_zscrew_on    valid 0 .. 1 " in text and "derived input spindle_on~delay10" in text


@pytest.mark.parametrize(
    "um, counts",
    [
        (0.0, 0),
        (0.04, 0),
        (0.05, 1),
        (-0.05, -1),
        (0.15, 2),
        (0.25, 3),
        (-0.25, -3),
        (12.34, 123),
        (-12.36, -124),
        (2999.96, 30000),
        (5000.0, 30000),
        (-1e9, -30000),
    ],
)
def test_counts_at_01_um_round_halves_away_from_zero_and_saturate(um, counts):
    assert IntegerForm(0.1, 30000).counts(um) == counts


def test_other_integer_forms_and_their_range():
    whole = IntegerForm(resolution_um=1.0, limit=32767)
    assert whole.counts(2.5) == 3 and whole.counts(-2.5) == -3 and whole.counts(40000.0) == 32767
    assert IntegerForm().range_um == 3000.0 and IntegerForm().um(123) == 12.3
    with pytest.raises(ValueError):
        IntegerForm().counts(math.nan)
    with pytest.raises(InputError):
        IntegerForm(resolution_um=0.0)
    with pytest.raises(InputError):
        IntegerForm(limit=0)


def test_sinumerik_conversions():
    assert sinumerik_abs_value_mm(-12.5) == -0.0125
    assert sinumerik_temp_comp_type() == 1
    assert sinumerik_temp_comp_type(position_dependent=True) == 3
    assert sinumerik_temp_comp_type(position_independent=False, tool_direction=True) == 4
    # K0 = 0.010 mm, tanb = 2e-5, P0 = 100 mm: at P = 600 mm, 10 µm + 2e-5 * 500 mm = 20 µm
    assert sinumerik_total_um(0.010, 2e-5, 600.0, 100.0) == pytest.approx(20.0)
    with pytest.raises(ValueError):
        sinumerik_abs_value_mm(math.inf)


def test_sheet_states_units_sign_limits_and_registers():
    model, _ = synthetic_model()
    section = model["switching"]
    sheet = controller_sheet(RuleTables.from_model(model))
    assert sheet["sinumerik"]["MD32750_TEMP_COMP_TYPE"] == 1
    assert sheet["sinumerik"]["SD43900_TEMP_COMP_ABS_VALUE"]["unit"] == "mm"
    assert sheet["sinumerik"]["SD43910_TEMP_COMP_SLOPE"]["value"] == 0.0
    assert sheet["output"]["rate_limit_um_per_sample"] == section["rate_limit_um"]
    assert sheet["integer"]["clamp_counts"] == [round(section["comp_min_um"] * 10), round(section["comp_max_um"] * 10)]
    text = render(model, "sheet")["groupfit_sheet.txt"]
    for needle in ("MD32750", "SD43900", "SD43910", "SD43920", "MD32760", "C / 1000", "Sign:", "counts"):
        assert needle in text
    small = controller_sheet(RuleTables.from_model(model), IntegerForm(0.1, 100))
    assert small["integer"]["clamp_exceeds_register"] is True


def test_export_command_writes_every_target(tmp_path, capsys):
    model, _ = synthetic_model()
    write_model(model, tmp_path / "model.json")
    out = tmp_path / "export"
    assert (
        main(
            [
                "export",
                str(tmp_path / "model.json"),
                "--target",
                "all",
                "-o",
                str(out),
                "--real",
                "REAL",
                "--name",
                "FB_Spindle",
            ]
        )
        == 0
    )
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        [
            "groupfit_model.h",
            "groupfit_model.c",
            "FB_Spindle.st",
            "groupfit_runtime.json",
            "groupfit_sheet.txt",
            "groupfit_sheet.json",
        ]
    )
    assert "OF REAL" in (out / "FB_Spindle.st").read_text()
    assert "wrote" in capsys.readouterr().out


def test_export_refuses_a_bad_block_name_and_writes_nothing(tmp_path, capsys):
    model, _ = synthetic_model()
    write_model(model, tmp_path / "model.json")
    args = ["export", str(tmp_path / "model.json"), "--target", "st", "-o", str(tmp_path / "x"), "--name", "1 bad"]
    status = main(args)
    assert status == 2 and "block name" in capsys.readouterr().err and not (tmp_path / "x").exists()


def test_export_of_a_missing_model_is_one_line(tmp_path, capsys):
    assert main(["export", str(tmp_path / "none.json"), "--target", "c", "-o", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "model file not found" in err[0]
