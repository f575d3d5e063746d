"""The run-time switching rule (groupfit.runtime) against hand-computed cases and offline serving."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support import write_model
from test_switching_models import noisy, shifted, synthetic_model

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.grouping import hard_groups, serving_group_index, soft_groups
from groupfit.model import ModelFile
from groupfit.runtime import (
    FAULT_HELD,
    FAULT_SENSOR,
    RETURN_SENSOR_FAULT,
    RULE_KEYS,
    SWITCH_CRITERION,
    SWITCH_FORCED,
    RuleSettings,
    SwitchingRule,
    estimate_noise,
    replay_groups,
    rule_parameters,
    switch_windows,
)

N_TINY = 20


def tiny_temps():
    """A rises 1 °C per sample from 21, B falls 0.5 °C per sample from 29.5."""
    i = np.arange(1, N_TINY + 1, dtype=float)
    return np.column_stack([20.0 + i, 30.0 - 0.5 * i])


def tiny_model(criterion_index=0, temps=None):
    """Two groups, break after sample 10, n = 3: window 8…10."""
    temps = tiny_temps() if temps is None else temps
    model = {
        "format": "groupfit-model/1",
        "sampling_period_s": 100.0,
        "temps": ["A", "B"],
        "error": "error_um",
        "intercept": True,
        "objective": "sae",
        "p": 1,
        "n": 3,
        "c": 3.0,
        "n_samples": N_TINY,
        "breaks": [10],
        "hard_groups": [[1, 10], [11, 20]],
        "soft_groups": [[1, 10], [8, 20]],
        "coefficients": [[1.0, 2.0, 0.5], [5.0, -1.0, 0.25]],
        "objective_value": 0.0,
        "switching": {
            "criterion": ["A", "B"][criterion_index],
            "criterion_index": criterion_index,
            "criterion_series": [float(v) for v in temps[:, criterion_index]],
        },
    }
    model["switching"].update(rule_parameters(model, temps, criterion_index=criterion_index))
    return model


def by_hand(group, a, b):
    coefficients = [[1.0, 2.0, 0.5], [5.0, -1.0, 0.25]][group - 1]
    return coefficients[0] + coefficients[1] * a + coefficients[2] * b


def test_parameters_of_the_tiny_model_by_hand():
    section = tiny_model()["switching"]
    assert section["windows"] == [[8, 10]]
    assert section["thresholds_c"] == [28.0]  # A at sample 8
    assert section["directions"] == [1]  # A(10) - A(7) = 3 °C > margin
    assert section["noise_c"] == 0.05 and section["margin_c"] == pytest.approx(0.15)  # a straight line has no noise
    assert section["hold_samples"] == 3  # 300 s at 100 s
    assert section["temp_min_c"] == [6.0, 5.0] and section["temp_max_c"] == [55.0, 45.0]
    # offline |prediction| peaks at sample 7 (group 1): 1 + 2*27 + 0.5*26.5 = 68.25 -> clamp ceil(2 * 68.25)
    assert section["comp_min_um"] == -137.0 and section["comp_max_um"] == 137.0
    # largest same-group step: group 1, 2*1 + 0.5*(-0.5) = 1.75 µm -> 2 * 1.75
    assert section["rate_limit_um"] == 3.5
    assert set(RULE_KEYS) <= set(section)


def test_windows_with_and_without_overlap():
    assert switch_windows([10, 30], 3) == [[8, 10], [28, 30]]
    assert switch_windows([10], 0) == [[11, 11]]  # no overlap: the first sample of the next hard group
    assert switch_windows([10], 1) == [[10, 10]]


@pytest.mark.parametrize(
    "shift, expected_sample, expected_kind",
    [
        (0, 8, SWITCH_CRITERION),
        (1, 9, SWITCH_CRITERION),
        (2, 10, SWITCH_FORCED),
        (3, 10, SWITCH_FORCED),
        (-1, 8, SWITCH_CRITERION),
        (-3, 8, SWITCH_CRITERION),
    ],
)
def test_switch_sample_of_a_shifted_run_by_hand(shift, expected_sample, expected_kind):
    replay = SwitchingRule(tiny_model()).replay(shifted(tiny_temps(), shift))
    switches = replay.switch_samples()
    assert [s["i"] for s in switches] == [expected_sample]
    assert replay.switched[expected_sample - 1] == expected_kind
    assert list(replay.group) == [1] * (expected_sample - 1) + [2] * (N_TINY - expected_sample + 1)


def test_predictions_by_hand():
    temps = tiny_temps()
    replay = SwitchingRule(tiny_model()).replay(temps)
    expected = []
    for i in range(1, N_TINY + 1):  # the switch at sample 8, then the bumpless transfer over n = 3 samples
        new = by_hand(1 if i < 8 else 2, *temps[i - 1])
        if i == 8:
            gap = expected[-1] - new  # from the last output to the new group's first prediction
        share = {8: 0.75, 9: 0.5, 10: 0.25}.get(i, 0.0)
        expected.append(new + share * gap if share else new)
    assert replay.prediction_um.tolist() == expected


def test_falling_criterion_switches_when_it_has_fallen_to_the_threshold():
    model = tiny_model(criterion_index=1)
    assert model["switching"]["directions"] == [-1] and model["switching"]["thresholds_c"] == [26.0]
    # one sample late: B is 26.5 at sample 8 (0.5 above the threshold, more than the 0.15 margin), 26.0 at 9
    assert [s["i"] for s in SwitchingRule(model).replay(shifted(tiny_temps(), 1)).switch_samples()] == [9]


def test_flat_criterion_switches_by_index():
    temps = tiny_temps()
    temps[5:12, 0] = 28.0  # A flat through the window: it cannot tell the operating state
    model = tiny_model(temps=temps)
    assert model["switching"]["directions"] == [0]
    live = tiny_temps()
    live[:, 0] = 21.0  # far below the threshold, still switches at the window's first sample
    replay = SwitchingRule(model).replay(live)
    assert replay.switch_samples() == [{"i": 8, "from": 1, "to": 2, "forced": False}]


def test_criterion_that_never_arrives_is_forced_at_the_window_end():
    live = tiny_temps()
    live[:, 0] = 21.0
    replay = SwitchingRule(tiny_model()).replay(live)
    assert replay.switch_samples() == [{"i": 10, "from": 1, "to": 2, "forced": True}]


def test_rate_limit_and_clamp_by_hand():
    model = tiny_model()
    model["switching"]["blend_samples"] = 0  # a hard switch: the rate limit spreads the jump
    replay = SwitchingRule(model).replay(tiny_temps())
    # target -57.75 µm at sample 1: the compensation ramps by 3.5 µm per sample
    assert replay.compensation_um[:7].tolist() == [-3.5 * k for k in range(1, 8)]
    # group 2 predicts -16.5 µm at sample 8: target +16.5, the ramp turns at the same rate
    assert replay.compensation_um[7] == -24.5 + 3.5
    model["switching"]["comp_min_um"], model["switching"]["comp_max_um"] = -10.0, 10.0
    replay = SwitchingRule(model).replay(tiny_temps())
    assert replay.compensation_um.min() == -10.0 and replay.compensation_um.max() == 10.0
    assert np.max(np.abs(np.diff(np.r_[0.0, replay.compensation_um]))) <= 3.5


def test_held_readings_then_sensor_fault_then_recovery():
    temps = tiny_temps()
    temps[2:5, 1] = np.nan  # samples 3, 4, 5: held (K = 3)
    temps[10:14, 1] = np.inf  # samples 11…14: held 3, then a fault at 14
    rule = SwitchingRule(tiny_model())
    replay = rule.replay(temps)
    assert replay.fault.tolist()[:6] == [0, 0, FAULT_HELD, FAULT_HELD, FAULT_HELD, 0]
    assert replay.prediction_um[2] == by_hand(1, temps[2, 0], temps[1, 1])  # last good B (sample 2)
    assert replay.prediction_um[4] == by_hand(1, temps[4, 0], temps[1, 1])
    assert replay.fault.tolist()[10:15] == [FAULT_HELD] * 3 + [FAULT_SENSOR, 0]
    assert replay.prediction_um[13] == 0.0  # safe output
    before = replay.compensation_um[12]
    assert replay.compensation_um[13] == before + np.clip(0.0 - before, -3.5, 3.5)  # ramping towards 0
    assert replay.prediction_um[14] == by_hand(2, *temps[14])  # recovered
    rule.reset()
    result = [rule.step(row) for row in temps][13]
    assert result.code == RETURN_SENSOR_FAULT and result.group == 2


def test_invalid_before_any_good_reading_is_a_fault_at_once():
    temps = tiny_temps()
    temps[0, 0] = np.nan
    replay = SwitchingRule(tiny_model()).replay(temps)
    assert replay.fault[0] == FAULT_SENSOR and replay.prediction_um[0] == 0.0 and replay.fault[1] == 0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, 1e300, -1e300, 1e-300, 56.0, 5.9])
def test_every_kind_of_invalid_reading_is_held(bad):
    temps = tiny_temps()
    temps[3, 0] = bad
    replay = SwitchingRule(tiny_model()).replay(temps)
    assert replay.fault[3] == FAULT_HELD
    assert replay.prediction_um[3] == by_hand(1, temps[2, 0], temps[3, 1])


def test_criterion_in_fault_falls_back_to_the_index():
    live = shifted(tiny_temps(), 3)  # would be forced at 10 on the criterion
    live[1:9, 0] = np.nan  # criterion invalid from sample 2: in fault from sample 5
    replay = SwitchingRule(tiny_model()).replay(live)
    assert replay.switch_samples() == [{"i": 8, "from": 1, "to": 2, "forced": False}]
    assert replay.fault[7] == FAULT_SENSOR


def test_sampling_period_is_checked():
    model = tiny_model()
    SwitchingRule(model, period_s=100.9)  # within 1 %
    with pytest.raises(InputError, match="sampling period 102 s differs from the model's 100 s"):
        SwitchingRule(model, period_s=102.0)
    with pytest.raises(InputError):
        SwitchingRule(model, period_s=float("nan"))


def test_wrong_number_of_temperatures_is_refused():
    with pytest.raises(InputError, match="the model takes 2"):
        SwitchingRule(tiny_model()).step([20.0])


def test_model_file_carries_the_rule_and_replays_the_offline_grouping():
    model, run = synthetic_model()
    section = model["switching"]
    assert set(RULE_KEYS) <= set(section)
    assert section["criterion_series"] == run.temps[:, section["criterion_index"]].tolist()
    series = np.asarray(section["criterion_series"])
    for (first, last), threshold, direction in zip(section["windows"], section["thresholds_c"], section["directions"]):
        assert threshold == series[first - 1]
        change = series[last - 1] - series[first - 2]
        assert direction == (0 if abs(change) <= section["margin_c"] else np.sign(change))
    assert section["blend_samples"] == model["n"]
    hard = SwitchingRule({**model, "switching": {**section, "blend_samples": 0}}).replay(run.temps)
    offline = serving_group_index(model["breaks"], run.n_samples, model["n"]) + 1
    assert np.array_equal(hard.group, offline)
    coefficients = np.asarray(model["coefficients"])
    by_group = coefficients[:, 0][None, :] + run.temps @ coefficients[:, 1:].T  # (N, G): every group's prediction
    expected = by_group[np.arange(run.n_samples), offline - 1]
    assert np.max(np.abs(hard.prediction_um - expected)) < 1e-9
    residual = run.error - hard.prediction_um
    assert np.sqrt(np.mean(residual**2)) == pytest.approx(model["training"]["rms_um"], rel=1e-9)
    # the bumpless rule: the same groups, and at the switch's k-th sample (k = 1 … n) the new group's
    # prediction plus (n + 1 - k)/(n + 1) of the gap from the last output before the switch to it
    replay = SwitchingRule(model).replay(run.temps)
    assert np.array_equal(replay.group, offline)
    for switch in np.flatnonzero(np.diff(offline)) + 1:
        gap = expected[switch - 1] - expected[switch]
        for k in range(1, model["n"] + 1):
            expected[switch + k - 1] += (model["n"] + 1 - k) / (model["n"] + 1) * gap
    assert np.max(np.abs(replay.prediction_um - expected)) < 1e-9


@pytest.mark.parametrize("seed", range(5))
def test_sensor_noise_of_005_c_does_not_move_the_switches(seed):
    model, run = synthetic_model()
    clean = SwitchingRule(model).replay(run.temps)
    replay = SwitchingRule(model).replay(noisy(run.temps, 0.05, seed))
    assert np.array_equal(replay.group, clean.group)
    assert np.sqrt(np.mean((replay.prediction_um - clean.prediction_um) ** 2)) < 0.5


@pytest.mark.parametrize("shift", [-3, -2, -1, 0, 1, 2, 3])
def test_runs_up_to_n_samples_early_or_late_switch_inside_the_windows(shift):
    model, run = synthetic_model()
    windows = model["switching"]["windows"]
    switches = SwitchingRule(model).replay(shifted(run.temps, shift)).switch_samples()
    assert [s["to"] for s in switches] == [2, 3, 4]
    for s, (first, last) in zip(switches, windows):
        assert first <= s["i"] <= last
    if shift <= 0:  # an early run is past each threshold when its window opens
        assert [s["i"] for s in switches] == [w[0] for w in windows]


def test_late_runs_switch_later_on_a_rising_criterion():
    model, run = synthetic_model()
    active = [k for k, d in enumerate(model["switching"]["directions"]) if d != 0]
    assert active, "the synthetic model should have at least one criterion-driven window"
    samples = [
        [SwitchingRule(model).replay(shifted(run.temps, s)).switch_samples()[k]["i"] for k in active]
        for s in range(0, 4)
    ]
    assert samples == sorted(samples) and samples[-1] != samples[0]


def test_single_precision_tracks_double():
    model, run = synthetic_model()
    double = SwitchingRule(model).replay(run.temps)
    single = SwitchingRule(model, precision="single").replay(run.temps)
    assert np.array_equal(single.group, double.group)
    assert np.max(np.abs(single.prediction_um - double.prediction_um)) < 1e-3
    assert single.prediction_um.tolist() == [float(np.float32(v)) for v in single.prediction_um]


def test_older_model_files_without_rule_keys_still_replay(tmp_path):
    model, run = synthetic_model()
    full = SwitchingRule(model).replay(run.temps)
    for key in RULE_KEYS:
        del model["switching"][key]
    write_model(model, tmp_path / "old.json")
    old = ModelFile.load(tmp_path / "old.json").to_dict()
    rule = SwitchingRule(old)
    series = model["switching"]["criterion_series"]
    assert rule.tables.thresholds_c == tuple(series[w[0] - 1] for w in full_windows(old))
    assert np.array_equal(rule.replay(run.temps).group, full.group)


def full_windows(model):
    return switch_windows(model["breaks"], model["n"])


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("windows", [[5, 3]], "switching.windows"),
        ("directions", [2, 0, 0], "switching.directions"),
        ("temp_min_c", [0.0], "switching.temp_min_c must be a list of 4"),
        ("rate_limit_um", 0.0, "switching.rate_limit_um must be positive"),
        ("criterion_index", 9, "switching.criterion_index"),
    ],
)
def test_broken_rule_keys_are_refused_on_loading(tmp_path, key, value, message):
    model, _ = synthetic_model()
    model["switching"][key] = value
    write_model(model, tmp_path / "bad.json")
    with pytest.raises(InputError, match=message):
        ModelFile.load(tmp_path / "bad.json").to_dict()


@pytest.mark.parametrize(
    "low, high, message",
    [
        (30.0, 30.0, "comp_min_um must be less than comp_max_um"),
        (10.0, 48.0, "switching.comp_min_um = 10.0: above 0, the clamp never lets the compensation be 0"),
        (-48.0, -5.0, "switching.comp_max_um = -5.0: below 0"),
    ],
)
def test_a_clamp_that_serves_no_zero_is_refused_by_replay_and_export(tmp_path, capsys, low, high, message):
    """A hand-edited clamp with no width, or one that excludes 0, would move the axis whatever the model says."""
    model, _ = synthetic_model()
    model["switching"].update(comp_min_um=low, comp_max_um=high)
    write_model(model, tmp_path / "bad.json")
    assert main(["export", str(tmp_path / "bad.json"), "--target", "c", "--out", str(tmp_path / "c")]) == 2
    assert message in capsys.readouterr().err and not (tmp_path / "c").exists()
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        ModelFile.load(tmp_path / "bad.json").to_dict()
    model["switching"].update(comp_min_um=0.0, comp_max_um=high if high > 0 else 5.0)
    write_model(model, tmp_path / "one_sided.json")
    assert ModelFile.load(tmp_path / "one_sided.json").switching.comp_min_um == 0.0


def test_noise_estimate_recovers_white_noise_on_a_smooth_curve():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 10, 2000)
    assert estimate_noise(20 + 5 * np.sin(t) + 0.2 * rng.standard_normal(t.size)) == pytest.approx(0.2, rel=0.1)
    assert estimate_noise(np.linspace(20, 30, 50)) == pytest.approx(0.0, abs=1e-12)


def test_settings_change_the_derived_parameters():
    model = tiny_model()
    section = rule_parameters(model, tiny_temps(), criterion_index=0, settings=RuleSettings(hold_s=1000.0, noise_c=0.5))
    assert section["hold_samples"] == 10 and section["margin_c"] == pytest.approx(1.5)


@st.composite
def model_and_stream(draw):
    n = draw(st.integers(0, 6))
    n_breaks = draw(st.integers(0, 4))
    # every hard group longer than n and than its M = 3 coefficients, as a valid model file has them
    gaps = draw(st.lists(st.integers(max(n, 3) + 1, 15), min_size=n_breaks, max_size=n_breaks))
    breaks = [int(b) for b in np.cumsum(gaps)]
    length = 70
    series = np.cumsum(draw(st.lists(st.floats(-1, 1), min_size=length, max_size=length)))
    temps = np.column_stack([20 + series, np.linspace(20, 25, length)])
    model = tiny_model(temps=temps)
    model.update(
        p=len(breaks),
        n=n,
        breaks=breaks,
        n_samples=length,
        hard_groups=[list(g) for g in hard_groups(breaks, length)],
        soft_groups=[list(g) for g in soft_groups(breaks, length, n)],
        coefficients=[[float(g), 1.0, -1.0] for g in range(len(breaks) + 1)],
    )
    model["switching"]["criterion_series"] = [float(v) for v in temps[:, 0]]
    model["switching"].update(rule_parameters(model, temps, criterion_index=0))
    live = temps + np.asarray(draw(st.lists(st.floats(-3, 3), min_size=length, max_size=length)))[:, None]
    bad_rows = draw(st.lists(st.integers(0, length - 1), max_size=15))
    values = draw(
        st.lists(
            st.sampled_from([np.nan, np.inf, -np.inf, 1e300, 1e-300]), min_size=len(bad_rows), max_size=len(bad_rows)
        )
    )
    for row, value in zip(bad_rows, values):
        live[row, 0] = value
    return model, live


@settings(max_examples=60, deadline=None)
@given(model_and_stream())
def test_one_group_per_sample_never_backwards_never_stalls(case):
    model, live = case
    replay = SwitchingRule(model).replay(live)
    steps = np.diff(np.r_[1, replay.group])
    assert set(np.unique(steps)) <= {0, 1}
    assert np.array_equal(steps, (replay.switched > 0).astype(int))
    previous = 0
    for (first, last), s in zip(model["switching"]["windows"], replay.switch_samples()):
        assert first <= s["i"] <= max(last, previous + 1)
        previous = s["i"]
    reached = [w for w in model["switching"]["windows"] if w[1] + len(model["breaks"]) <= len(live)]
    assert len(replay.switch_samples()) >= len(reached)
    assert np.all(np.isfinite(replay.prediction_um)) and np.all(np.isfinite(replay.compensation_um))


def test_model_dict_is_json_ready():
    model, _ = synthetic_model()
    json.dumps(model, allow_nan=False)


def test_replay_groups_are_the_rule_groups_from_zero():
    model, run = synthetic_model()
    temps = shifted(run.temps, 2)
    assert np.array_equal(replay_groups(model, temps), SwitchingRule(model).replay(temps).group - 1)
