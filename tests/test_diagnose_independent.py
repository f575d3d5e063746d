"""The diagnosis on runs nobody here tuned it on: an independent lumped RC machine (``bench/independent_machine.py``).

The simulator shares no code with ``groupfit.synthetic`` or ``groupfit.fe``.
Each scenario has one known missing effect (or none, or two); the truth is
the simulator's, the judge the validation run.
"""

import pytest
from support import independent_machine as machine
from support.bench_modules import load

bench = load("bench_diagnose_independent")

ONE_OF_EACH = {"amb_T_amb_30s", "pump_45min_30s_pure", "speed_rpm_2h_30s_pure", "none_30s", "pump_45min_30s"}
"""The fast lane's share: an ambient, an on/off source, a speed-driven lag, nothing missing, two at once."""
DEFAULT_REFERENCE = {"amb_T_amb_30s", "none_30s", "pump_45min_30s"}


def scenario_names(fast: set[str]) -> list:
    names = [spec.name for spec in machine.scenario_specs()]
    return [name if name in fast else pytest.param(name, marks=pytest.mark.slow) for name in names]


@pytest.mark.parametrize("name", scenario_names(ONE_OF_EACH))
def test_the_right_effect_first_and_the_next_run_better_by_40_percent(name):
    row = bench.measure(machine.scenarios([name])[0])
    before, after = row["validation_rms_before_um"], row["validation_rms_after_um"]
    # never reported better when it is worse
    assert row["improved"] is (None if not row["added"] else after < before)
    assert row["report_first_line"].startswith("the augmented model is worse") is bool(row["added"] and after >= before)
    assert row["verdict"] == "OK", row


@pytest.mark.parametrize("name", scenario_names(DEFAULT_REFERENCE))
def test_from_the_fits_default_reference_too(name):
    """Fitted as ``groupfit fit`` does by default (rises over T_amb) on a machine that feels absolute temperatures:
    a reference kept wrongly hides the effect, so the diagnosis on absolute readings must win where it is wrong."""
    row = bench.measure(machine.scenarios([name])[0], reference="default")
    before, after = row["validation_rms_before_um"], row["validation_rms_after_um"]
    assert row["improved"] is (None if not (row["added"] or row["reference_dropped"]) else after < before)
    assert row["verdict"] == "OK", row


def test_a_fall_the_oracle_cannot_reach_is_told_from_a_miss():
    """The right effect, validation better by 20 %: out of reach when the oracle does no better, else a FAIL."""
    from types import SimpleNamespace

    pump = SimpleNamespace(missing=("pump_on",))
    right = [{"column": "pump_on"}]
    assert bench.verdict(pump, right, 10.0, 8.0, True, oracle=7.0).startswith(
        "out of reach: fell 20 %, the oracle 30 %"
    )
    assert bench.verdict(pump, right, 10.0, 8.0, True, oracle=3.0) == "FAIL: validation fell only 20 %"
    # never out of reach when the effect is the wrong one, or the validation got worse
    assert bench.verdict(pump, [{"column": "T_amb"}], 10.0, 8.0, True, oracle=9.0).startswith("FAIL: first effect")
    assert bench.verdict(pump, right, 10.0, 11.0, False, oracle=9.0) == "worse, reported so"
    assert bench.verdict(pump, right, 10.0, 5.0, True, oracle=9.0) == "OK"
