"""Structured Text export: parses with blark and tree-sitter, and behaves like the C build.

The block's behaviour is checked by the evaluator over tree-sitter's tree of ``tests/support/structured_text.py``.
"""

from __future__ import annotations

import math
import shutil
from functools import lru_cache

import numpy as np
import pytest
from support.replay import assert_same_decisions as assert_same_replay
from support.replay import python_replay
from support.structured_text import (
    FunctionBlock,
    STError,
    as_single,
    assert_same_decisions,
    blark_accepts,
    run_block,
    tree_sitter_errors,
)
from test_switching_models import (
    augmented_model,
    derived_streams,
    eight_sensor_model,
    streams_for,
    synthetic_model,
)

from groupfit.export import render, write
from groupfit.export.harness import build_driver, run_driver
from groupfit.runtime import FAULT_PERIOD, RETURN_PERIOD_FAULT, RETURN_SENSOR_FAULT, SwitchingRule

pytestmark = pytest.mark.toolchain


@lru_cache(maxsize=None)
def models():
    return {
        "synthetic p=3": synthetic_model()[0],
        "p=0": synthetic_model(p=0)[0],
        "8 temps p=6": eight_sensor_model()[0],
    }


def block_source(label: str, real: str) -> str:
    (text,) = render(models()[label], "st", real=real).values()
    return text


@pytest.mark.parametrize(
    "label, real",
    [
        ("synthetic p=3", "REAL"),
        ("synthetic p=3", "LREAL"),
        ("p=0", "REAL"),
        ("8 temps p=6", "REAL"),
    ],
)
@pytest.mark.slow
def test_generated_blocks_parse_with_both_parsers(tmp_path, label, real):
    model = models()[label]
    files = render(model, "st", real=real)
    (path,) = write(files, tmp_path)
    text = path.read_text(encoding="ascii")
    assert path.name == "FB_GroupfitComp.st" and f"ARRAY[1..{len(model['temps'])}] OF {real}" in text
    assert blark_accepts(text), f"blark rejects the {label} block"
    assert not tree_sitter_errors(text), f"tree-sitter rejects the {label} block"


BREAKAGES = {
    "unbalanced bracket in a declaration": lambda s: s.replace("ARRAY[1..4] OF REAL;", "ARRAY[1..4 OF REAL;", 1),
    "missing semicolon in a declaration": lambda s: s.replace("Reset : BOOL;", "Reset : BOOL", 1),
    "missing semicolon in the body": lambda s: s.replace("comp := comp + delta;", "comp := comp + delta", 1),
}
MORE_BREAKAGES = {
    "missing END_IF": lambda s: s.replace("END_IF;", "", 1),
    "misspelt END_FOR": lambda s: s.replace("END_FOR;", "END_FRO;", 1),
    "unbalanced bracket in the body": lambda s: s.replace("COEF_0[currentGroup]", "COEF_0[currentGroup", 1),
    "dangling operator": lambda s: s.replace("delta := target - comp;", "delta := target - ;", 1),
}


@pytest.mark.parametrize("breakage", sorted(BREAKAGES))
@pytest.mark.slow
def test_broken_copies_fail_both_parsers(breakage):
    text = block_source("p=0", "REAL")
    broken = BREAKAGES[breakage](text)
    assert broken != text
    assert not blark_accepts(broken)
    assert tree_sitter_errors(broken)


@pytest.mark.parametrize("breakage", sorted(MORE_BREAKAGES))
def test_tree_sitter_rejects_more_broken_copies(breakage):
    text = block_source("synthetic p=3", "REAL")
    broken = MORE_BREAKAGES[breakage](text)
    assert broken != text and tree_sitter_errors(broken)


# behaviour ------------------------------------------------------------------


@pytest.fixture(scope="module")
def single_driver(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    built = {}

    def get(label, model):
        if label not in built:
            folder = tmp_path_factory.mktemp("c_" + label.replace(" ", "_").replace("=", ""))
            write(render(model, "c"), folder)
            built[label] = build_driver(folder, folder / "driver", single=True)
        return built[label]

    return get


STREAMS = {"synthetic p=3": None, "p=0": ("modelling", "faults"), "8 temps p=6": ("modelling", "faults")}


ST_LABELS = [pytest.param(k, marks=pytest.mark.slow) if k == "8 temps p=6" else k for k in sorted(STREAMS)]
"""The largest block (six breaks on eight sensors) takes the longest to parse: the full suite runs it."""


@pytest.mark.parametrize("label", ST_LABELS)
def test_real_block_matches_the_single_precision_c_build_bit_for_bit(single_driver, label):
    model = models()[label]
    run = eight_sensor_model()[1] if len(model["temps"]) == 8 else synthetic_model()[1]
    chosen = STREAMS[label]
    streams = as_single([v for k, v in streams_for(model, run).items() if chosen is None or k in chosen])
    st_out = run_block(block_source(label, "REAL"), streams, model["sampling_period_s"], "REAL")
    c_out = run_driver(single_driver(label, model), streams)
    assert_same_decisions(st_out, c_out)


def test_a_reading_within_half_a_single_step_beyond_its_limit_is_decided_alike_in_single_precision(single_driver):
    """A REAL block rounds a reading to single before it tests its range (its inputs are REAL): a reading just
    beyond a limit is then at the limit, valid. The C float build and the Python rule in single round it
    first too, and decide the same; in double it is beyond the limit: held, then a sensor fault."""
    model, run = synthetic_model()
    high, low = model["switching"]["temp_max_c"][0], model["switching"]["temp_min_c"][1]
    temps = run.temps.astype(float).copy()
    temps[30:34, 0] = np.nextafter(high, np.inf)  # beyond the limit in double, at it in single
    temps[50:53, 1] = np.nextafter(low, -np.inf)
    assert np.float32(temps[30, 0]) == np.float32(high) and np.float32(temps[50, 1]) == np.float32(low)
    single, double = python_replay(model, temps, "single"), python_replay(model, temps)
    for rows in (slice(30, 34), slice(50, 53)):
        assert (single["fault"][rows] == 0).all() and (double["fault"][rows] != 0).all()  # held, then a fault
    (st_out,) = run_block(block_source("synthetic p=3", "REAL"), [temps], model["sampling_period_s"], "REAL")
    (c_out,) = run_driver(single_driver("synthetic p=3", model), [temps])
    assert_same_decisions([st_out], [c_out])
    assert_same_replay(c_out, single)


def test_lreal_block_matches_the_python_rule():
    model, run = synthetic_model()
    streams = list(streams_for(model, run).values())
    rule = SwitchingRule(model)
    outputs = run_block(block_source("synthetic p=3", "LREAL"), streams, model["sampling_period_s"], "LREAL")
    for temps, out in zip(streams, outputs):
        rule.reset()
        results = [rule.step(row) for row in temps]
        assert out["code"].tolist() == [r.code for r in results]
        assert out["fault"].tolist() == [r.fault for r in results]
        assert np.max(np.abs(out["prediction_um"] - [r.prediction_um for r in results])) <= 1e-9
        assert np.max(np.abs(out["compensation_um"] - [r.compensation_um for r in results])) <= 1e-9


def test_wrong_task_period_holds_a_period_fault_and_ramps_to_zero():
    model, run = synthetic_model()
    block = FunctionBlock(block_source("synthetic p=3", "LREAL"))
    for k in range(20):
        block.call(Temps=[np.float64(v) for v in run.temps[k]], SamplePeriodS=100.0, Reset=(k == 0))
    before = float(block.vars["CompUm"])
    assert block.vars["Group"] == 1 and before < 0
    rate = model["switching"]["rate_limit_um"]
    block.call(Temps=[np.float64(v) for v in run.temps[20]], SamplePeriodS=60.0, Reset=False)
    assert block.vars["Group"] == RETURN_PERIOD_FAULT and block.vars["Fault"] == FAULT_PERIOD
    assert float(block.vars["CompUm"]) == pytest.approx(min(0.0, before + rate))
    assert block.vars["sampleCount"] == 20  # the count stands still while the period is wrong
    block.call(Temps=[np.float64(v) for v in run.temps[20]], SamplePeriodS=100.0, Reset=False)
    assert block.vars["Group"] == 1 and block.vars["sampleCount"] == 21


def test_evaluator_traps_an_unguarded_index():
    source = """FUNCTION_BLOCK FB_Probe
VAR_INPUT
    k : INT;
END_VAR
VAR_OUTPUT
    ok : BOOL;
END_VAR
VAR CONSTANT
    LIMIT : ARRAY[1..2] OF INT := [5, 6];
END_VAR
ok := k <= 2 AND LIMIT[k] > 0;
END_FUNCTION_BLOCK
"""
    block = FunctionBlock(source)
    block.call(k=1)
    assert block.vars["ok"] is True
    with pytest.raises(STError, match="index 3 outside"):
        block.call(k=3)  # AND evaluates LIMIT[3] although k <= 2 is FALSE


# derived inputs ---------------------------------------------------------------


@lru_cache(maxsize=None)
def derived_block(label: str, real: str) -> str:
    (text,) = render(augmented_model(label)[0], "st", real=real).values()
    return text


@pytest.mark.parametrize("label, real", [("all kinds p=2", "REAL"), ("on/off p=1", "LREAL")])
@pytest.mark.slow
def test_blocks_with_derived_inputs_parse_with_both_parsers(label, real):
    text = derived_block(label, real)
    assert text.isascii() and "derivedValue" in text and "LOWPASS_A_1" in text
    assert blark_accepts(text), f"blark rejects the {label} block"
    assert not tree_sitter_errors(text), f"tree-sitter rejects the {label} block"


def test_real_block_with_derived_inputs_matches_the_single_precision_c_build_bit_for_bit(single_driver):
    model, run = augmented_model("all kinds p=2")
    streams = as_single(list(derived_streams(model, run).values()))
    st_out = run_block(derived_block("all kinds p=2", "REAL"), streams, model["sampling_period_s"], "REAL")
    c_out = run_driver(single_driver("derived all kinds", model), streams)
    assert_same_decisions(st_out, c_out)


def test_lreal_block_with_derived_inputs_matches_the_python_rule():
    model, run = augmented_model("on/off p=1")
    streams = list(derived_streams(model, run).values())
    rule = SwitchingRule(model)
    outputs = run_block(derived_block("on/off p=1", "LREAL"), streams, model["sampling_period_s"], "LREAL")
    for temps, out in zip(streams, outputs):
        rule.reset()
        results = [rule.step(row) for row in temps]
        assert out["code"].tolist() == [r.code for r in results]
        assert out["fault"].tolist() == [r.fault for r in results]
        assert out["switched"].tolist() == [r.switched for r in results]
        assert np.max(np.abs(out["prediction_um"] - [r.prediction_um for r in results])) <= 1e-9
        assert np.max(np.abs(out["compensation_um"] - [r.compensation_um for r in results])) <= 1e-9


def test_reset_restarts_the_derived_inputs():
    model, run = augmented_model("on/off p=1")
    raw = derived_streams(model, run)["modelling"][:40]
    block = FunctionBlock(derived_block("on/off p=1", "LREAL"))
    first = []
    for k, row in enumerate(raw):
        block.call(Temps=[np.float64(v) for v in row], SamplePeriodS=100.0, Reset=(k == 0))
        first.append(float(block.vars["ErrorUm"]))
    again = []
    for k, row in enumerate(raw):
        block.call(Temps=[np.float64(v) for v in row], SamplePeriodS=100.0, Reset=(k == 0))
        again.append(float(block.vars["ErrorUm"]))
    assert again == first and block.vars["delayPos2"] == 40 % 10


def test_on_time_real_block_matches_the_single_precision_c_build_bit_for_bit(single_driver):
    model, run = augmented_model("on-time p=1")
    streams = derived_streams(model, run)
    text = derived_block("on-time p=1", "REAL")
    assert "ONTIME_STEP_1 : REAL := " in text and "derivedMemory[1] := derivedMemory[1] + ONTIME_ONE;" in text
    single = as_single(list(streams.values()))
    st_out = run_block(text, single, model["sampling_period_s"], "REAL")
    assert_same_decisions(st_out, run_driver(single_driver("derived on-time", model), single))


@pytest.mark.slow
def test_on_time_lreal_block_makes_the_python_rules_decisions():
    """Another case of the LREAL evaluation of derived inputs (the fast lane's is the on/off block)."""
    model, run = augmented_model("on-time p=1")
    streams = derived_streams(model, run)
    rule = SwitchingRule(model)
    outputs = run_block(derived_block("on-time p=1", "LREAL"), list(streams.values()), 100.0, "LREAL")
    for temps, out in zip(streams.values(), outputs):
        rule.reset()
        results = [rule.step(row) for row in temps]
        assert out["code"].tolist() == [r.code for r in results]
        assert np.max(np.abs(out["prediction_um"] - [r.prediction_um for r in results])) <= 1e-9


@pytest.mark.slow
def test_on_time_blocks_parse_with_both_parsers():
    for real in ("REAL", "LREAL"):
        text = derived_block("on-time p=1", real)
        assert blark_accepts(text) and not tree_sitter_errors(text), f"a parser rejects the on-time {real} block"


# power stage and start from rest ------------------------------------------------


def heat_law_streams():
    model, run = augmented_model("heat law p=2")
    streams = derived_streams(model, run)
    r = 4  # speed_rpm, the source of the power stages
    late_start = streams["modelling"].copy()
    late_start[:6, r] = [np.nan, -1.0, np.inf, 1e12, -np.inf, np.nan]
    streams["speed faulty at the start"] = late_start
    return model, streams


@pytest.mark.parametrize("real", ["REAL", "LREAL"])
def test_heat_law_blocks_raise_the_speed_in_long_reals_from_rest(real):
    text = derived_block("heat law p=2", real)
    assert text.isascii() and "EXPT(ABS(" in text and "POWER_EXPONENT_1 : LREAL := 1.6666666666666667;" in text
    if real == "REAL":
        assert "sourceValue := TO_REAL(EXPT(ABS(TO_LREAL(lastGood[5])) / POWER_SCALE_1, POWER_EXPONENT_1));" in text
    else:
        assert "sourceValue := EXPT(ABS(lastGood[5]) / POWER_SCALE_1, POWER_EXPONENT_1);" in text
    assert "derivedMemory[1] := 0.0;" in text and "delayLine3[j] := 0.0;" in text  # from rest
    assert "derivedMemory[4] := sourceValue;" in text  # steady
    assert not tree_sitter_errors(text), f"tree-sitter rejects the heat-law {real} block"


@pytest.mark.slow
@pytest.mark.parametrize("real", ["REAL", "LREAL"])
def test_heat_law_blocks_parse_with_blark(real):
    assert blark_accepts(derived_block("heat law p=2", real)), f"blark rejects the heat-law {real} block"


def test_real_heat_law_block_matches_the_single_precision_c_build_bit_for_bit(single_driver):
    model, streams = heat_law_streams()
    streams = as_single(list(streams.values()))
    st_out = run_block(derived_block("heat law p=2", "REAL"), streams, model["sampling_period_s"], "REAL")
    c_out = run_driver(single_driver("heat law", model), streams)
    assert_same_decisions(st_out, c_out)
    for temps, st_stream in zip(streams, st_out):
        single = SwitchingRule(model, precision="single").replay(temps)  # and the float32 Python rule
        assert st_stream["prediction_um"].tobytes() == single.prediction_um.tobytes()


def test_lreal_heat_law_block_is_the_python_rule_bit_for_bit():
    model, streams = heat_law_streams()
    rule = SwitchingRule(model)
    chosen = [streams[k] for k in ("modelling", "source faults", "speed faulty at the start")]
    outputs = run_block(derived_block("heat law p=2", "LREAL"), chosen, model["sampling_period_s"], "LREAL")
    for temps, out in zip(chosen, outputs):
        replay = rule.replay(temps)
        assert out["code"].tolist() == [RETURN_SENSOR_FAULT if f & 2 else g for g, f in zip(replay.group, replay.fault)]
        assert out["fault"].tolist() == replay.fault.tolist()
        assert out["switched"].tolist() == replay.switched.tolist()
        assert out["prediction_um"].tobytes() == replay.prediction_um.tobytes()
        assert out["compensation_um"].tobytes() == replay.compensation_um.tobytes()


PROBE = """FUNCTION_BLOCK FB_Probe
VAR_INPUT
    x : LREAL;
    k : LREAL;
END_VAR
VAR_OUTPUT
    y : LREAL;
    r : REAL;
END_VAR
VAR CONSTANT
    SCALE : LREAL := 1000.0;
END_VAR
$body
END_FUNCTION_BLOCK
"""


def probe(body: str) -> FunctionBlock:
    return FunctionBlock(PROBE.replace("$body", body))


def test_evaluator_knows_expt_abs_and_the_conversions_as_iec_61131_3_defines_them():
    block = probe("y := EXPT(ABS(x) / SCALE, k);\nr := TO_REAL(y);")
    block.call(x=-2500.0, k=5 / 3)
    assert block.vars["y"] == math.pow(2.5, 5 / 3) and type(block.vars["y"]) is np.float64
    assert block.vars["r"] == np.float32(math.pow(2.5, 5 / 3)) and type(block.vars["r"]) is np.float32
    block.call(x=0.0, k=2.0)
    assert block.vars["y"] == 0.0
    with pytest.raises(STError, match="is an error"):
        probe("y := EXPT(x, k);").call(x=-2.0, k=0.5)  # a negative base needs a whole exponent
    with pytest.raises(STError, match="is an error"):
        probe("y := EXPT(x, k);").call(x=0.0, k=-1.0)
    with pytest.raises(STError, match="narrowing needs TO_REAL"):
        probe("r := x;").call(x=1.0, k=1.0)  # no implicit LREAL -> REAL
    with pytest.raises(STError, match="EXPT of a float32"):
        probe("r := EXPT(TO_REAL(x), TO_REAL(k));").call(x=2.0, k=2.0)
