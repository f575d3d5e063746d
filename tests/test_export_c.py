"""C99 export: strict compile, same decisions as the Python rule, no crash on any input."""

from __future__ import annotations

import copy
import math
import re
import shutil
import subprocess

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.replay import assert_same_decisions, python_replay
from test_switching_models import (
    augmented_model,
    augmented_validation,
    derived_streams,
    eight_sensor_model,
    eight_sensor_validation,
    fe_model,
    fe_validation_runs,
    heat_law_runs,
    readings,
    streams_for,
    synthetic_model,
)

from groupfit.export import render, write
from groupfit.export.harness import STRICT_FLAGS, build_driver, run_driver
from groupfit.features import Feature
from groupfit.runtime import RETURN_PERIOD_FAULT, RuleTables

pytestmark = [pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed"), pytest.mark.toolchain]


def cases():
    synthetic, run = synthetic_model()
    eight, eight_run = eight_sensor_model()
    flat, _ = synthetic_model(p=0)
    return {
        "synthetic p=3": (synthetic, streams_for(synthetic, run)),
        "synthetic p=0": (flat, streams_for(flat, run)),
        "8 temps p=6": (eight, {**streams_for(eight, eight_run), "other cycle": eight_sensor_validation().temps}),
    }


@pytest.mark.parametrize("label", ["synthetic p=3", "synthetic p=0", "8 temps p=6"])
def test_double_build_makes_the_decisions_of_replay(drivers, label):
    model, streams = cases()[label]
    outputs = run_driver(drivers(label, model), list(streams.values()))
    for temps, c_out in zip(streams.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps), tolerance=1e-9)


@pytest.mark.parametrize("label", ["synthetic p=3", "8 temps p=6"])
def test_single_precision_build_matches_the_float32_reference_bit_for_bit(drivers, label):
    model, streams = cases()[label]
    outputs = run_driver(drivers(label, model, "single"), list(streams.values()))
    for temps, c_out in zip(streams.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps, "single"))


@pytest.mark.slow
def test_fe_data_sets_replay_identically(drivers):
    model, run = fe_model()
    streams = {**streams_for(model, run), **{r.name: r.temps for r in fe_validation_runs(model)}}
    double = run_driver(drivers("fe", model), list(streams.values()))
    single = run_driver(drivers("fe", model, "single"), list(streams.values()))
    for temps, c_double, c_single in zip(streams.values(), double, single):
        assert_same_decisions(c_double, python_replay(model, temps), tolerance=1e-9)
        assert_same_decisions(c_single, python_replay(model, temps, "single"))


def test_the_header_names_the_build_it_is_bit_for_bit_with_and_refuses_fast_math(tmp_path):
    """An integrator receives the two files alone: they say to build without contraction, and a -ffast-math
    build (no NaN test, reassociated sums) stops with the reason."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    model, _ = cases()["synthetic p=3"]
    write(render(model, "c"), tmp_path)
    header = (tmp_path / "groupfit_model.h").read_text()
    assert "-ffp-contract=off" in header and "-std=c99" in header
    with pytest.raises(subprocess.CalledProcessError) as refused:
        build_driver(tmp_path, tmp_path / "driver", flags=("-O2", "-ffast-math"))
    assert "built with -ffast-math" in refused.value.stderr


def test_sanitized_build_runs_fault_streams_cleanly(drivers):
    model, streams = cases()["8 temps p=6"]
    executable = drivers("8 temps p=6", model, "sanitized")
    assert b"__asan_init" in executable.read_bytes() and b"__ubsan" in executable.read_bytes()
    outputs = run_driver(executable, list(streams.values()))
    for temps, c_out in zip(streams.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps), tolerance=1e-9)


SPECIAL = [np.nan, np.inf, -np.inf, 1e308, -1e308, 1e-308, -1e-308, 5e-324, 0.0, -0.0, 3.4e38, 1e39]


@st.composite
def hostile_stream(draw, n_temps):
    length = draw(st.integers(1, 60))
    base = draw(st.floats(0.0, 60.0))
    rows = []
    for _ in range(length):
        row = []
        for _ in range(n_temps):
            if draw(st.booleans()):
                row.append(draw(st.sampled_from(SPECIAL)))
            else:
                row.append(base + draw(st.floats(-5.0, 5.0)))
        rows.append(row)
    return np.array(rows, dtype=float)


@pytest.fixture(scope="module")
def hostile_setup(drivers):
    model, _ = synthetic_model()
    return model, drivers("synthetic p=3", model, "sanitized"), drivers("synthetic p=3", model, "single")


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stream=hostile_stream(4))
def test_nan_inf_huge_and_tiny_readings_never_crash_it(hostile_setup, stream):
    model, sanitized, single = hostile_setup
    (c_out,) = run_driver(sanitized, [stream])  # check=True: a sanitizer report fails the run
    assert_same_decisions(c_out, python_replay(model, stream), tolerance=1e-9)
    assert np.all(np.isfinite(c_out.prediction_um)) and np.all(np.isfinite(c_out.compensation_um))
    (c_single,) = run_driver(single, [stream])
    assert_same_decisions(c_single, python_replay(model, stream, "single"))


def test_header_documents_the_api(tmp_path):
    model, _ = eight_sensor_model()
    files = render(model, "c")
    header, source = files["groupfit_model.h"], files["groupfit_model.c"]
    assert "#define GF_N_TEMPS 8" in header and "#define GF_N_GROUPS 7" in header
    for m, name in enumerate(model["temps"]):
        assert f"temps[{m}] = {name}" in header
    assert "void gf_init(gf_state *s);" in header
    assert "int gf_step(gf_state *s, const double temps[GF_N_TEMPS], double *error_um);" in header
    includes = re.findall(r"#include\s+[<\"]([^>\"]+)[>\"]", header + source)
    assert includes == ["groupfit_model.h"]  # nothing but its own header: no library needed at all
    assert not re.search(r"\b(malloc|calloc|realloc|free)\b", source)
    hidden = re.findall(r"^static (?!const)(?![\w\s*]+\()", source, flags=re.M)  # helper functions may be static
    assert hidden == []  # tables are const, no hidden state
    assert header.isascii() and source.isascii()


def test_period_check(tmp_path):
    model, _ = synthetic_model()
    write(render(model, "c"), tmp_path)
    (tmp_path / "check.c").write_text(
        '#include <math.h>\n#include <stdio.h>\n#include "groupfit_model.h"\n'
        'int main(void) { printf("%d %d %d %d\\n", gf_check_period(100.0), gf_check_period(100.9), '
        "gf_check_period(102.0), gf_check_period(NAN)); return 0; }\n"
    )
    subprocess.run(
        [
            "gcc",
            *STRICT_FLAGS,
            "-I",
            str(tmp_path),
            str(tmp_path / "check.c"),
            str(tmp_path / "groupfit_model.c"),
            "-o",
            str(tmp_path / "check"),
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    out = subprocess.run([str(tmp_path / "check")], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["0", "0", str(RETURN_PERIOD_FAULT), str(RETURN_PERIOD_FAULT)]


# derived inputs ---------------------------------------------------------------

DERIVED = ["lowpass p=0", "all kinds p=2", "on/off p=1", "on-time p=1"]


def derived_case(label):
    model, run = augmented_model(label)
    streams = derived_streams(model, run)
    streams["validation"] = readings(model, augmented_validation(label))
    return model, streams


@pytest.mark.parametrize("label", DERIVED)
def test_derived_inputs_double_build_makes_the_decisions_of_replay(drivers, label):
    model, streams = derived_case(label)
    outputs = run_driver(drivers(label, model), list(streams.values()))
    worst = 0.0
    for temps, c_out in zip(streams.values(), outputs):
        py = python_replay(model, temps)
        assert_same_decisions(c_out, py, tolerance=1e-9)
        worst = max(worst, float(np.max(np.abs(c_out.prediction_um - py["prediction_um"]))))
    print(f"{label}: largest |C double - Python| = {worst:.3g} um")


@pytest.mark.parametrize("label", DERIVED)
def test_derived_inputs_single_build_matches_the_float32_reference_bit_for_bit(drivers, label):
    model, streams = derived_case(label)
    outputs = run_driver(drivers(label, model, "single"), list(streams.values()))
    for temps, c_out in zip(streams.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps, "single"))


def test_derived_inputs_sanitized_build_runs_fault_streams_cleanly(drivers):
    model, streams = derived_case("all kinds p=2")
    chosen = [streams["faults"], streams["source faults"]]
    outputs = run_driver(drivers("all kinds p=2", model, "sanitized"), chosen)
    for temps, c_out in zip(chosen, outputs):
        assert_same_decisions(c_out, python_replay(model, temps), tolerance=1e-9)


def test_header_documents_the_readings_and_the_derived_inputs():
    model, _ = augmented_model("all kinds p=2")
    tables = RuleTables.from_model(model)
    header, source = render(model, "c").values()
    assert "#define GF_N_TEMPS 7 " in header and "#define GF_N_INPUTS 9 " in header
    assert "#define GF_N_DERIVED 5 " in header and "#define GF_DELAY_2 3 " in header
    for r, name in enumerate(tables.raw_names):
        assert f"temps[{r}] = {name}" in header
    assert "temps[4] = T_amb  [7, 36]  (source of T_amb~lp1800s, T_amb~ddt)" in header
    assert "int gf_step(gf_state *s, const double temps[GF_N_TEMPS], double *error_um);" in header
    assert "gf_real line_2[GF_DELAY_2];" in header
    # the low-pass coefficient is a constant computed once, the same for every target
    a = tables.derived[0].a
    assert f"gf_lowpass_a_0 = GF_R({a:.17e}, {float(np.float32(a)):.9e}f);" in source
    includes = re.findall(r"#include\s+[<\"]([^>\"]+)[>\"]", header + source)
    assert includes == ["groupfit_model.h"]
    assert re.findall(r"^static (?!const)(?![\w\s*]+\()", source, flags=re.M) == []  # static helpers only
    code = re.sub(r"/\*.*?\*/", "", source, flags=re.S)
    assert not re.search(r"\b(malloc|calloc|realloc|free|exp)\s*\(", code)


# power stage and start from rest ------------------------------------------------

HEAT = "heat law p=2"


def heat_law_streams(model):
    """The derived streams, the validation run, and the speed invalid before its first good reading."""
    _, streams = derived_case(HEAT)
    tables = RuleTables.from_model(model)
    r = tables.raw_names.index("speed_rpm")
    late_start = streams["modelling"].copy()
    late_start[:6, r] = [np.nan, -1.0, np.inf, 1e12, -np.inf, np.nan]
    streams["speed faulty at the start"] = late_start
    huge = streams["validation"].copy()
    huge[100:110, r] = [1e308, -1e308, 5e-324, 0.0, -0.0, 3.4e38, 1e39, np.nan, 1e-300, 12000.0]
    streams["huge and tiny speeds"] = huge
    return streams


def test_heat_law_and_rest_start_double_build_is_the_python_rule_bit_for_bit(drivers):
    model, _ = augmented_model(HEAT)
    streams = heat_law_streams(model)
    outputs = run_driver(drivers(HEAT, model), list(streams.values()))
    samples = 0
    for temps, c_out in zip(streams.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps))  # %a: every bit
        samples += len(temps)
    assert set(streams) >= {"modelling", "validation", "faults", "source faults", "speed faulty at the start"}
    print(f"{HEAT}: {len(streams)} streams, {samples} samples bit for bit (double)")


def test_heat_law_and_rest_start_float_build_is_the_float32_rule_bit_for_bit(drivers):
    model, _ = augmented_model(HEAT)
    streams = heat_law_streams(model)
    outputs = run_driver(drivers(HEAT, model, "single"), list(streams.values()))
    for temps, c_out in zip(streams.values(), outputs):
        assert_same_decisions(c_out, python_replay(model, temps, "single"))


def test_heat_law_sanitized_build_runs_fault_streams_cleanly(drivers):
    model, _ = augmented_model(HEAT)
    streams = heat_law_streams(model)
    chosen = [streams[k] for k in ("faults", "source faults", "speed faulty at the start", "huge and tiny speeds")]
    outputs = run_driver(drivers(HEAT, model, "sanitized"), chosen)
    for temps, c_out in zip(chosen, outputs):
        assert_same_decisions(c_out, python_replay(model, temps))


@pytest.fixture(scope="module")
def heat_law_setup(drivers):
    model, _ = augmented_model(HEAT)
    return model, drivers(HEAT, model, "sanitized"), drivers(HEAT, model, "single")


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stream=hostile_stream(6))
def test_hostile_readings_of_a_heat_law_source_never_crash_it(heat_law_setup, stream):
    model, sanitized, single = heat_law_setup
    with np.errstate(over="ignore"):
        stream[:, 4] = np.where(np.isfinite(stream[:, 4]), np.abs(stream[:, 4]) * 100.0, stream[:, 4])  # a speed
    (c_out,) = run_driver(sanitized, [stream])
    assert_same_decisions(c_out, python_replay(model, stream))
    assert np.all(np.isfinite(c_out.prediction_um)) and np.all(np.isfinite(c_out.compensation_um))
    (c_single,) = run_driver(single, [stream])
    assert_same_decisions(c_single, python_replay(model, stream, "single"))


def test_power_stage_uses_math_h_in_double_and_rest_starts_at_zero():
    model, _ = augmented_model(HEAT)
    header, source = render(model, "c").values()
    includes = re.findall(r"#include\s+[<\"]([^>\"]+)[>\"]", header + source)
    assert includes == ["math.h", "groupfit_model.h"]  # the C standard library, nothing else
    assert "static const double gf_power_scale_0 = 1.00000000000000000e+03;" in source
    assert f"static const volatile double gf_power_exponent_0 = {5 / 3:.17e};" in source
    assert "v = (gf_real)pow(fabs((double)s->last[4]) / gf_power_scale_0, gf_power_exponent_0);" in source
    code = re.sub(r"/\*.*?\*/", "", source, flags=re.S)
    assert len(re.findall(r"\bpow\(", code)) == 3 and not re.search(r"\b(powf|fabsf|exp)\s*\(", code)
    assert "s->memory[0] = 0;\n    }" in code  # the heat-law low-pass starts from rest
    assert "s->line_2[j] = 0;" in code and "s->memory[3] = v;" in code  # delay from rest; steady low-pass
    assert "derived[2] = T_amb~delay3r: T_amb delayed by 3 sample(s), from rest" in header
    assert header.isascii() and source.isascii()
    # a model without a power stage still needs no library at all
    plain = render(augmented_model("all kinds p=2")[0], "c")["groupfit_model.c"]
    assert "#include <math.h>" not in plain and "pow(" not in plain


def test_heat_law_scenario_starts_at_speed():
    modelling, validation = heat_law_runs()
    assert modelling["speed_rpm"].iloc[0] > 0 and validation["speed_rpm"].iloc[0] > 0
    assert modelling["speed_rpm"].nunique() > 3


def exposing_power(model: dict, k: int, exponent: float) -> dict:
    """The model with derived input ``k``'s exponent changed, predicting that input itself (every other coefficient 0).

    Its prediction is then the power stage's value bit for bit, so a last-bit
    difference in the power is not lost in the dot product.
    """
    model = copy.deepcopy(model)
    entry = model["derived_inputs"][k]
    old = entry["name"]
    entry["exponent"] = exponent
    entry["name"] = Feature.from_dict(entry).name
    j = model["temps"].index(old)
    model["temps"][j] = entry["name"]
    width = len(model["coefficients"][0])
    model["coefficients"] = [[1.0 if m == j + 1 else 0.0 for m in range(width)] for _ in model["coefficients"]]
    model["switching"]["comp_min_um"], model["switching"]["comp_max_um"] = -1e6, 1e6
    model["switching"]["blend_samples"] = 0  # a switch's transfer would spread the input's own step
    return model


@pytest.mark.parametrize("exponent", [2.0, pytest.param(4 / 3, marks=pytest.mark.slow)])
def test_a_constant_exponent_is_not_folded_into_multiplications(tmp_path, exponent):
    """gcc -O2 turns pow(x, 2.0) into x*x, which differs from the C library's pow in the last bit of ~0.1 %
    of squares; the exponent is a volatile constant, so every build calls pow as the Python rule does."""
    model = exposing_power(augmented_model(HEAT)[0], 1, exponent)
    raw = readings(model, augmented_validation(HEAT))
    rng = np.random.default_rng(7)
    stream = raw[rng.integers(0, len(raw), 20000)]
    stream[:, 4] = rng.uniform(0.0, 12000.0, len(stream))  # speeds that are no round numbers
    write(render(model, "c"), tmp_path)
    for single in (False, True):
        executable = build_driver(tmp_path, tmp_path / f"driver_{single}", single=single)
        (c_out,) = run_driver(executable, [stream])
        py = python_replay(model, stream, "single" if single else "double")
        assert_same_decisions(c_out, py)
    expected = [math.pow(v / 1000.0, exponent) for v in stream[:, 4]]
    assert python_replay(model, stream)["prediction_um"].tolist() == expected  # the prediction is the power itself
