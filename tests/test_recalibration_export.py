"""Probe checks on the controller: gf_probe in C, Probe/ProbeErrorUm in Structured Text and the JSON table's
recalibration object make the decisions of the Python rule bit for bit, gross readings and faults included."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from recalibration_cases import probe_cases
from support.json_runtime import run_table

from groupfit.export import render, write
from groupfit.export.harness import build_driver
from groupfit.export.probe_harness import PROBE_DRIVER_C, run_probe_driver
from groupfit.runtime import PROBE_APPLIED, PROBE_CODE_OFFSET, SwitchingRule

CASES = probe_cases()


def python_replay(model, temps, probes, precision="double"):
    replay = SwitchingRule(model, precision=precision).replay(temps, probes)
    return replay, replay.probe[replay.probe != 0] - PROBE_CODE_OFFSET


def test_the_cases_exercise_every_outcome_of_a_check():
    seen = {"applied": 0, "rejected": 0, "ignored": 0}
    for model, streams, probes in CASES.values():
        for temps, checks in zip(streams, probes):
            for key, count in python_replay(model, temps, checks)[0].probe_counts().items():
                seen[key] += count
    assert all(count > 0 for count in seen.values()), seen


def test_the_clamp_case_carries_the_output_beyond_the_models_clamp_and_no_further():
    model, streams, probes = CASES["synthetic p=3 beyond the clamp"]
    limit = model["switching"]["comp_max_um"]
    bound = limit + model["recalibration"]["offset_max_um"]
    for temps, checks in zip(streams, probes):
        output = np.abs(python_replay(model, temps, checks)[0].compensation_um)
        assert limit < output.max() <= bound
        assert np.abs(SwitchingRule(model).replay(temps).compensation_um).max() <= limit  # without checks
        rule = SwitchingRule(model)
        rule.replay(temps, checks)
        assert limit < rule.recal.clamp_high <= bound  # the checks widened the model's own clamp too


def test_the_kalman_cases_leave_corrections_both_applied_and_held_back_as_not_significant():
    states = set()
    for label, (model, streams, probes) in CASES.items():
        if not label.endswith("kalman"):
            continue
        for temps, checks in zip(streams, probes):
            rule = SwitchingRule(model)
            for row, check in zip(temps, checks):
                rule.step(row)
                if not np.isnan(check) and rule.probe(check) == PROBE_APPLIED:
                    states.add(rule.recal.significant)
    assert states == {True, False}


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
@pytest.mark.toolchain
@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("label", sorted(CASES))
def test_gf_probe_is_the_python_rule_bit_for_bit(tmp_path, label, precision):
    model, streams, probes = CASES[label]
    write(render(model, "c"), tmp_path)
    executable = build_driver(tmp_path, tmp_path / "driver", single=precision == "single", driver_source=PROBE_DRIVER_C)
    for (c_out, codes), temps, checks in zip(run_probe_driver(executable, streams, probes), streams, probes):
        replay, expected = python_replay(model, temps, checks, precision)
        assert np.array_equal(codes, expected)
        assert np.array_equal(c_out.fault, replay.fault) and np.array_equal(c_out.group, replay.group)
        assert c_out.prediction_um.tobytes() == replay.prediction_um.tobytes()
        assert c_out.compensation_um.tobytes() == replay.compensation_um.tobytes()


def test_the_header_declares_gf_probe_and_its_codes():
    model, _, _ = CASES["synthetic p=3 kalman"]
    header = render(model, "c")["groupfit_model.h"]
    assert "int gf_probe(gf_state *s, double measured_error_um);" in header
    for name, value in (("APPLIED", "1"), ("REJECTED", "0"), ("IGNORED", "(-1)")):
        assert f"#define GF_PROBE_{name} {value}" in header
    assert "SD43900" in header


@pytest.mark.parametrize("label", sorted(CASES))
def test_the_json_table_alone_takes_checks_as_the_python_rule_does(label):
    model, streams, probes = CASES[label]
    table = json.loads(render(model, "json")["groupfit_runtime.json"])
    for temps, checks in zip(streams, probes):
        codes = []
        out = run_table(table, temps, checks, codes)
        replay, expected = python_replay(model, temps, checks)
        assert np.array_equal(codes, expected)
        assert np.array([o[2] for o in out]).tobytes() == replay.prediction_um.tobytes()
        assert np.array([o[3] for o in out]).tobytes() == replay.compensation_um.tobytes()


def test_the_sheet_names_the_setting_datum_of_a_probe_cycle(tmp_path):
    model, _, _ = CASES["lowpass p=0 hold"]
    written = write(render(model, "sheet"), tmp_path)
    text = next(p for p in written if p.suffix == ".txt").read_text()
    sheet = json.loads(next(p for p in written if p.suffix == ".json").read_text())
    assert "Probe checks (offset hold)" in text and "SD43900 TEMP_COMP_ABS_VALUE" in text
    assert sheet["probe_checks"]["setting_datum"].startswith("SD43900")


@pytest.mark.slow
@pytest.mark.toolchain
@pytest.mark.parametrize("real", ["REAL", "LREAL"])
@pytest.mark.parametrize(
    "label, samples",
    [("lowpass p=0 kalman", 160), ("synthetic p=3 beyond the clamp", None), ("synthetic p=3 held at the clamp", None)],
)
def test_the_structured_text_block_takes_checks_as_the_python_rule_does(real, label, samples):
    blocks = pytest.importorskip("support.structured_text")
    model, streams, probes = CASES[label]
    block = blocks.FunctionBlock(render(model, "st", real=real)["FB_GroupfitComp.st"])
    cast = blocks.FLOATS[real]
    for temps, checks in list(zip(streams, probes))[:2]:
        temps, checks = temps[:samples], checks[:samples]
        predictions, outputs, codes = [], [], []
        for k, (row, check) in enumerate(zip(temps, checks)):
            with np.errstate(over="ignore", invalid="ignore"):
                block.call(
                    Temps=[cast(v) for v in row],
                    SamplePeriodS=model["sampling_period_s"],
                    Reset=k == 0,
                    Probe=not np.isnan(check),
                    ProbeErrorUm=0.0 if np.isnan(check) else float(check),
                )
            predictions.append(float(block.vars["ErrorUm"]))
            outputs.append(float(block.vars["CompUm"]))
            if not np.isnan(check):
                codes.append(int(block.vars["ProbeResult"]))
        replay, expected = python_replay(model, temps, checks, "single" if real == "REAL" else "double")
        assert np.array_equal(codes, expected)
        assert np.array(predictions).tobytes() == replay.prediction_um.tobytes()
        assert np.array(outputs).tobytes() == replay.compensation_um.tobytes()
