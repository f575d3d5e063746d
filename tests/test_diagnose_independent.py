"""The diagnosis on runs nobody here tuned it on: an independent lumped RC machine (``bench/independent_machine.py``).

The simulator shares no code with ``groupfit.synthetic`` or ``groupfit.fe``.
Each scenario has one known missing effect (or none, or two); the truth is
the simulator's, the judge the validation run.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"


def load(name):
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


machine = load("independent_machine")
bench = load("bench_diagnose_independent")


@pytest.mark.parametrize("name", [spec.name for spec in machine.scenario_specs()])
def test_the_right_effect_first_and_the_next_run_better_by_40_percent(name):
    row = bench.measure(machine.scenarios([name])[0])
    before, after = row["validation_rms_before_um"], row["validation_rms_after_um"]
    # never reported better when it is worse
    assert row["improved"] is (None if not row["added"] else after < before)
    assert row["report_first_line"].startswith("the augmented model is worse") is bool(row["added"] and after >= before)
    assert row["verdict"] == "OK", row
