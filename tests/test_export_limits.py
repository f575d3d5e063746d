"""Every exported integer constant fits the type it is declared with, in C and in Structured Text.

A model sampled every 5 ms holds a faulty reading for 300 s = 60 000
samples: more than a 16-bit ``INT`` holds. The Structured Text must declare
those counters ``DINT``, the C ``long`` (``int`` may be 16 bits), the C
must build under ``-Wconversion``, and the C routine must hold a reading
for all 60 000 samples as the Python rule does. A hold no 32-bit counter
keeps is refused by the model validator, naming the limit; a reserved word
is refused as the function block's name.
"""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main
from groupfit.controller_limits import DINT_MAX, INT_MAX, MAX_HOLD_SAMPLES
from groupfit.errors import InputError
from groupfit.export import render, write
from groupfit.export.harness import build_driver, run_driver
from groupfit.model import ModelFile
from groupfit.runtime import FAULT_HELD, FAULT_SENSOR, SwitchingRule

ST_RANGES = {"SINT": 2**7 - 1, "INT": INT_MAX, "DINT": DINT_MAX, "LINT": 2**63 - 1}
C_RANGES = {"int": INT_MAX, "long": DINT_MAX}
"""The least each declared type holds: the IEC 61131-3 sizes, and the C standard's minimums (int 16, long 32 bits)."""


@pytest.fixture(scope="module")
def fast_model(tmp_path_factory):
    """A model fitted by ``groupfit fit`` on the synthetic run sampled every 5 ms (the default 300 s hold)."""
    folder = tmp_path_factory.mktemp("fast")
    frame = pd.read_csv(SYNTHETIC)
    frame["time_s"] = np.arange(len(frame)) * 0.005
    frame.to_csv(folder / "fast.csv", index=False)
    argv = ["fit", "--quiet", "--data", str(folder / "fast.csv"), "--temps", "T1,T2,T3,T4", "--p", "2"]
    assert main([*argv, "--search", "exact", "--out", str(folder)]) == 0
    return json.loads((folder / "model.json").read_text())


def st_integers(text: str):
    """(name, type, value) of every integer constant or initial value the Structured Text declares."""
    types = "|".join(ST_RANGES)
    for name, kind, value in re.findall(rf"^\s*(\w+)\s*:\s*({types})\s*:=\s*(-?\d+)\s*;", text, flags=re.M):
        yield name, kind, int(value)
    pattern = rf"^\s*(\w+)\s*:\s*ARRAY\[[^\]]*\]\s+OF\s+({types})\s*:=\s*\[([^\]]*)\]"
    for name, kind, values in re.findall(pattern, text, flags=re.M):
        for value in values.split(","):
            yield name, kind, int(value)


def c_integers(header: str, source: str):
    """(name, type, value) of every integer table the C declares, and of every counter a macro initialises."""
    for kind, name, values in re.findall(r"static const (int|long) (\w+)\[[^\]]*\] = \{([^}]*)\}", source):
        for value in values.split(","):
            yield name, kind, int(value.strip().rstrip("L"))
    macros = {k: int(v) for k, v in re.findall(r"#define (GF_\w+) (-?\d+)L?\b", header)}
    fields = {name: kind for kind, name in re.findall(r"^\s+(int|long) (\w+)(?:\[[^\]]*\])?;", header, flags=re.M)}
    for field, macro, offset in re.findall(r"s->(\w+)(?:\[\w+\])? = (GF_\w+)(?: \+ (\d+))?;", source):
        if field in fields:  # an integer counter (a real field, such as the clamp, is no integer)
            yield field, fields[field], macros[macro] + int(offset or 0)


def test_a_5_ms_model_declares_dint_counters_and_every_constant_fits(fast_model):
    hold = fast_model["switching"]["hold_samples"]
    assert hold == 60000  # floor(300 s / 5 ms)
    st = render(fast_model, "st")["FB_GroupfitComp.st"]
    declared = list(st_integers(st))
    assert ("HOLD_SAMPLES", "DINT", hold) in declared and ("badCount", "DINT", hold + 1) in declared
    assert all(abs(value) <= ST_RANGES[kind] for _, kind, value in declared), [
        d for d in declared if abs(d[2]) > ST_RANGES[d[1]]
    ]
    files = render(fast_model, "c")
    c_declared = list(c_integers(files["groupfit_model.h"], files["groupfit_model.c"]))
    assert ("bad", "long", hold + 1) in c_declared
    assert all(abs(value) <= C_RANGES[kind] for _, kind, value in c_declared)
    # a model of the usual 100 s period keeps the 16-bit INT where it fits
    slow, _ = synthetic_model()
    assert ("HOLD_SAMPLES", "INT", 3) in list(st_integers(render(slow, "st")["FB_GroupfitComp.st"]))


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
def test_the_c_of_a_5_ms_model_builds_with_conversion_warnings_and_holds_60000_samples(fast_model, tmp_path):
    write(render(fast_model, "c"), tmp_path)
    driver = build_driver(tmp_path, tmp_path / "driver", flags=("-O1", "-Wconversion"))
    hold = fast_model["switching"]["hold_samples"]
    frame = pd.read_csv(SYNTHETIC)
    readings = frame[fast_model["temps"]].to_numpy()[:1].repeat(hold + 10, axis=0)
    readings[5:, 1] = np.nan  # T2 fails after 5 samples: held for `hold` samples, then a fault
    (c_out,) = run_driver(driver, [readings])
    python = SwitchingRule(fast_model).replay(readings)
    np.testing.assert_array_equal(c_out.fault, python.fault)
    assert c_out.fault[4] == 0 and c_out.fault[5 + hold - 1] & FAULT_HELD  # held for `hold` samples …
    assert c_out.fault[5 + hold] & FAULT_SENSOR and not c_out.fault[5 + hold - 1] & FAULT_SENSOR  # … then a fault


def test_a_hold_no_32_bit_counter_keeps_is_refused_naming_the_limit():
    model, _ = synthetic_model()
    model["switching"]["hold_samples"] = MAX_HOLD_SAMPLES + 1
    with pytest.raises(InputError, match=f"0…{MAX_HOLD_SAMPLES}"):
        ModelFile.coerce(model).checked()
    model["switching"]["hold_samples"] = MAX_HOLD_SAMPLES
    st = render(model, "st")["FB_GroupfitComp.st"]
    assert all(abs(v) <= ST_RANGES[k] for _, k, v in st_integers(st))


@pytest.mark.parametrize(
    "name", ["END_FUNCTION_BLOCK", "end_var", "INT", "HOLD_SAMPLES", "Temps", "1st", "a-b", "FB__Comp", "FB_", "_"]
)
def test_a_reserved_or_taken_name_is_refused_as_the_block_name(name):
    model, _ = synthetic_model()
    with pytest.raises(InputError, match="block name"):
        render(model, "st", name=name)
