"""A part whose error grows with the hours a spindle has run at speed: the speed × on-time candidate."""

import numpy as np
import pandas as pd
from support.diagnose_scenarios import global_model

from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.features import Feature, lowpass
from groupfit.runtime import replay_groups

ON_TIME = Feature("speed_rpm", "ontime", exponent=5 / 3, scale=1000.0, start="rest")
MODELLING = [(5000, 3000), (3000, 0), (6000, 5000), (4000, 0), (4000, 2000), (3000, 0), (8000, 4000), (5000, 0)]
VALIDATION = [(7000, 4000), (4000, 0), (3000, 2500), (2000, 0), (9000, 3500), (6000, 0), (5000, 5000), (2000, 0)]
"""Spindle schedules (duration s, r/min) with stops between runs: an on-time starts again at each."""


def spindle_run(schedule, seed, period_s=60.0):
    """Sensors lag the bearing heat over a drifting air; the error adds 0.8 µm per unit of :data:`ON_TIME`."""
    rng = np.random.default_rng(seed)
    ends = np.cumsum([d for d, _ in schedule])
    t = np.arange(0.0, ends[-1], period_s)
    speed = np.array([n for _, n in schedule], dtype=float)[np.searchsorted(ends, t, side="right")]
    heat = (speed / 1000.0) ** (5 / 3)
    air = 20.0 + 1.0 * np.sin(2 * np.pi * t / 50000.0)
    table = {"time_s": t, "T_amb": air + 0.02 * rng.standard_normal(len(t)), "speed_rpm": speed}
    for name, (tau, gain) in {"T1": (400.0, 1.0), "T2": (1500.0, 0.8), "T3": (6000.0, 0.6)}.items():
        table[name] = air + gain * lowpass(heat, tau, period_s, 0.0) + 0.02 * rng.standard_normal(len(t))
    error = 1.2 * table["T1"] + 0.7 * table["T2"] + 0.9 * table["T3"] + 0.8 * ON_TIME.compute(speed, period_s)
    table["error_um"] = error + 0.05 * rng.standard_normal(len(t))
    return pd.DataFrame(table)


def test_a_part_that_grows_with_the_hours_at_speed_is_named_as_speed_times_on_time():
    temps = ["T1", "T2", "T3"]
    modelling = load_run(spindle_run(MODELLING, 1), temps=temps, name="modelling")
    validation = load_run(spindle_run(VALIDATION, 2), temps=temps, name="validation")
    model = global_model(modelling)

    result = diagnose(model, modelling, validation, live_rule=replay_groups)
    first = result.added[0].feature
    assert (first.column, first.transform, first.exponent) == ("speed_rpm", "ontime", 5 / 3)
    before, after = result.before["validate"]["rms_um"], result.after["validate"]["rms_um"]
    assert after <= 0.4 * before and result.improved is True
    assert "heat law (x/1000)^1.67, times the hours on" in result.summary().splitlines()[0]
    # the augmented model's inputs are those the controller computes: replayed through the rule, as judged
    assert result.model.derived_inputs[0].transform == "ontime"
