"""Derived inputs in the run-time rule: readings, recursions, faults, valid ranges, model files.

The truths the rule is held to are independent of it: ``groupfit.features``
(each transform of a column) and ``groupfit.diagnose.residual.predict`` (the
model's offline prediction).
"""

import copy
import json
import math

import numpy as np
import pytest
from support import write_model
from test_switching_models import (
    HEAT_LAW,
    augmented_model,
    augmented_validation,
    readings,
    shifted,
    source_faults,
)

from groupfit.diagnose.residual import model_inputs, predict, residual
from groupfit.errors import InputError
from groupfit.features import Feature
from groupfit.grouping import bumpless, serving_group_index
from groupfit.model import ModelFile
from groupfit.runtime import (
    FAULT_HELD,
    FAULT_SENSOR,
    LEGACY_SOURCE_RANGE,
    RULE_KEYS,
    SOURCE_RANGES_KEY,
    RuleTables,
    SwitchingRule,
    replay_groups,
    source_valid_range,
)


def step_all(rule: SwitchingRule, raw: np.ndarray):
    """Results and model inputs (derived ones as the rule computed them) at every sample."""
    rule.reset()
    results, inputs = [], []
    for row in raw:
        results.append(rule.step(row))
        inputs.append(rule.input_values())
    return results, np.array(inputs)


def held_series(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """A column as the rule sees it: an invalid value replaced by the last valid one (NaN before any)."""
    out = np.array(values, dtype=float)
    last = np.nan
    for k, v in enumerate(out):
        if low <= v <= high:
            last = v
        out[k] = last
    return out


def test_readings_are_the_measured_inputs_then_the_sources_in_order_of_first_appearance():
    model, _ = augmented_model("all kinds p=2")
    tables = RuleTables.from_model(model)
    assert tables.input_names == (
        "T1",
        "T2",
        "T3",
        "T4",
        "T_amb~lp1800s",
        "T_amb~ddt",
        "speed_rpm~delay3",
        "T5",
        "T1~lp600s",
    )
    assert tables.raw_names == ("T1", "T2", "T3", "T4", "T_amb", "speed_rpm", "T5")
    assert [d.reading for d in tables.derived] == [4, 4, 5, 6, 0]  # T1~lp600s reads the measured T1
    assert tables.input_reading == (0, 1, 2, 3, -1, -1, -1, -1, -1)
    assert tables.input_derived == (-1, -1, -1, -1, 0, 1, 2, 3, 4)
    assert tables.criterion_reading == 0 and tables.n_temps == 7 and tables.n_inputs == 9
    assert tables.valid_origin == ("temperature",) * 4 + ("source",) * 3
    period = model["sampling_period_s"]
    lowpass = tables.derived[0]
    assert lowpass.a == np.exp(-period / 1800.0) and lowpass.b == 1.0 - lowpass.a
    assert tables.derived[1].scale == 3600.0 / period and tables.derived[2].delay_samples == 3


@pytest.mark.parametrize("which", ["modelling", "validation"])
def test_p0_rule_reproduces_the_offline_prediction(which):
    model, run = augmented_model("lowpass p=0")
    run = run if which == "modelling" else augmented_validation("lowpass p=0")
    replay = SwitchingRule(model).replay(readings(model, run))
    assert np.all(replay.fault == 0) and np.all(replay.group == 1)
    assert np.max(np.abs(replay.prediction_um - predict(model, run))) <= 1e-9


@pytest.mark.parametrize("label", ["all kinds p=2", "on/off p=1"])
def test_every_transform_matches_groupfit_features_and_the_offline_model(label):
    model, run = augmented_model(label)
    rule = SwitchingRule(model)
    results, inputs = step_all(rule, readings(model, run))
    # every model input, derived ones included, bit for bit as groupfit.features computes it
    assert np.array_equal(inputs, model_inputs(model, run))
    groups = np.array([r.group for r in results])
    offline = serving_group_index(model["breaks"], run.n_samples, model["n"]) + 1
    assert np.array_equal(groups, offline) and len(set(groups)) == model["p"] + 1
    prediction = np.array([r.prediction_um for r in results])
    # the offline model on the offline grouping, with the rule's bumpless transfer after each switch
    transferred = ModelFile.coerce(model).predict(inputs, offline - 1, transfer=True)
    assert np.max(np.abs(prediction - transferred)) <= 1e-9
    blending = np.abs(prediction - predict(model, run)) > 1e-9  # only the n samples after each switch differ
    assert set(np.flatnonzero(blending)) <= {s + k for s in np.flatnonzero(np.diff(offline)) + 1 for k in range(3)}


def assert_as_computed(actual: np.ndarray, expected: np.ndarray, feature: Feature, name: str) -> None:
    """Bit for bit; a power stage within 1e-14 relative (Feature.compute takes numpy's power, the rule the C pow)."""
    if feature.exponent is None:
        assert np.array_equal(actual, expected), name
    else:
        assert np.allclose(actual, expected, rtol=1e-14, atol=0.0), name


@pytest.mark.parametrize("label", ["all kinds p=2", "heat law p=2", "on-time p=1"])
def test_a_held_or_faulty_source_feeds_its_transform_with_the_last_good_value(label):
    model, run = augmented_model(label)
    tables = RuleTables.from_model(model)
    features = ModelFile.coerce(model).derived
    raw = source_faults(readings(model, run), tables)
    results, inputs = step_all(SwitchingRule(model), raw)
    period = model["sampling_period_s"]
    for d in tables.derived:
        seen = held_series(raw[:, d.reading], tables.valid_min[d.reading], tables.valid_max[d.reading])
        first = int(np.flatnonzero(np.isfinite(seen))[0])
        # the transform starts at the source's first good reading (from 0 when it starts from rest)
        expected = features[d.name].compute(seen[first:], period)
        assert_as_computed(inputs[first:, d.input_index], expected, features[d.name], d.name)
    fault = np.array([r.fault for r in results])
    hold = tables.hold_samples
    assert fault[0] == FAULT_SENSOR and results[0].prediction_um == 0.0  # T_amb not valid yet
    assert np.all(fault[30 : 30 + hold] == FAULT_HELD)  # T_amb held: output valid
    assert np.all(fault[200 : 200 + hold] == FAULT_HELD)
    assert np.all(fault[200 + hold : 200 + hold + 4] & FAULT_SENSOR)  # then a sensor fault: safe output
    assert all(results[k].prediction_um == 0.0 for k in range(200 + hold, 200 + hold + 4))
    assert fault[200 + hold + 4] == 0 or fault[200 + hold + 4] == FAULT_HELD  # recovered (speed may be held)
    assert fault[300] & FAULT_HELD and fault[301] & FAULT_HELD  # out of range: held
    # a valid output is the model with the rule's own inputs (with the bumpless transfer after a switch)
    coefficients = np.asarray(model["coefficients"])
    groups = np.array([r.group for r in results]) - 1
    served = coefficients[groups, 0] + np.einsum("ij,ij->i", coefficients[groups, 1:], inputs)
    switches = np.flatnonzero(np.diff(groups)) + 1
    assert not any((fault[s - 1 : s + model["n"]] & FAULT_SENSOR).any() for s in switches)  # as offline: no fault there
    expected = bumpless(served, groups, model["n"])
    valid = (fault & FAULT_SENSOR) == 0
    np.testing.assert_allclose(np.array([r.prediction_um for r in results])[valid], expected[valid], rtol=0, atol=1e-9)


def test_source_invalid_at_the_start_starts_its_transforms_at_its_first_good_reading():
    model, run = augmented_model("lowpass p=0")
    raw = readings(model, run)
    raw[:5, 4] = np.nan  # T_amb missing for the first five samples
    results, inputs = step_all(SwitchingRule(model), raw)
    assert [r.fault for r in results[:6]] == [FAULT_SENSOR] * 5 + [0]
    expected = Feature("T_amb", "lowpass", 1800.0).compute(raw[5:, 4], model["sampling_period_s"])
    assert np.array_equal(inputs[5:, 4], expected)


def test_heat_law_source_invalid_at_the_start_starts_from_rest_at_its_first_good_reading():
    model, run = augmented_model("heat law p=2")
    tables = RuleTables.from_model(model)
    r = tables.raw_names.index("speed_rpm")
    raw = readings(model, run)
    raw[:4, r] = [np.nan, -1.0, np.inf, 1e12]  # the speed is not valid before sample 5
    results, inputs = step_all(SwitchingRule(model), raw)
    assert [r.fault for r in results[:5]] == [FAULT_SENSOR] * 4 + [0]
    speed = raw[4:, r]
    assert speed[0] > 0  # the machine is at speed at its first good reading
    lowpass = tables.derived[0]
    assert lowpass.name == HEAT_LAW.name and lowpass.from_rest
    expected = HEAT_LAW.compute(speed, model["sampling_period_s"])
    assert np.allclose(inputs[4:, 4], expected, rtol=1e-14, atol=0.0)
    assert inputs[4, 4] == lowpass.b * math.pow(speed[0] / 1000.0, 5.0 / 3.0)  # b*x from a zero state
    steady = Feature("speed_rpm", "lowpass", tau_s=1800.0, exponent=5 / 3, scale=1000.0)
    assert abs(inputs[4, 4] - steady.compute(speed, model["sampling_period_s"])[0]) > 0.1  # the start matters here


@pytest.mark.parametrize("which", ["modelling", "validation"])
def test_heat_law_and_rest_start_replay_as_the_offline_model(which):
    model, run = augmented_model("heat law p=2")
    run = run if which == "modelling" else augmented_validation("heat law p=2")
    names = [d["name"] for d in model["derived_inputs"]]
    assert names == [
        "(speed_rpm/1000)^1.667~lp1800sr",
        "(speed_rpm/1000)^1.667",
        "T_amb~delay3r",
        "(speed_rpm/1000)^1.667~lp3600s",
    ]
    assert run.frame["speed_rpm"].iloc[0] > 0 and run.frame["T_amb"].iloc[0] > 0  # rest differs from steady
    results, inputs = step_all(SwitchingRule(model), readings(model, run))
    assert all(r.fault == 0 for r in results)
    truth = model_inputs(model, run)  # groupfit.features: Feature.compute of every derived input
    assert np.allclose(inputs, truth, rtol=1e-14, atol=0.0)
    assert np.array_equal(inputs[:3, 6], [0.0, 0.0, 0.0]) and inputs[3, 6] == run.frame["T_amb"].iloc[0]
    groups = np.array([r.group for r in results])
    served = ModelFile.coerce(model)
    offline = served.predict(truth, groups - 1, transfer=True)  # the model, with the groups the rule chose
    prediction = np.array([r.prediction_um for r in results])
    assert np.max(np.abs(prediction - offline)) <= 1e-9
    if which == "modelling":  # and the offline groups
        assert np.array_equal(groups - 1, served.serving_groups(len(truth)))


def test_power_stage_is_computed_in_double_and_rounded_to_single_once():
    model, run = augmented_model("heat law p=2")
    raw = readings(model, run)
    rule = SwitchingRule(model, precision="single")
    identity = RuleTables.from_model(model).derived[1]
    assert identity.transform == "identity" and identity.has_power
    for row in raw[:50]:
        rule.step(row)
        reading = float(np.float32(row[4]))  # the float32 reading, widened to double
        expected = np.float32(math.pow(abs(reading) / 1000.0, 5.0 / 3.0))
        assert rule.derived[1] == expected and type(rule.derived[1]) is np.float32
    double = SwitchingRule(model).replay(raw)
    single = SwitchingRule(model, precision="single").replay(raw)
    assert np.array_equal(single.group, double.group)
    assert np.max(np.abs(single.prediction_um - double.prediction_um)) < 1e-2


def test_a_power_stage_that_overflows_within_its_valid_range_is_refused():
    model, _ = augmented_model("heat law p=2")
    entry = model["derived_inputs"][1]
    entry["scale"] = 1e-30
    entry["name"] = Feature.from_dict(entry).name
    model["temps"][5] = entry["name"]
    with pytest.raises(InputError, match=r"power stage reaches .* valid range \[0, \d+\] of 'speed_rpm'"):
        RuleTables.from_model(model)


@pytest.mark.parametrize(
    "values, expected",
    [
        ([0, 1, 1, 0], (0.0, 1.0)),  # on/off signal
        ([0, 0, 0], (0.0, 1.0)),  # an on/off signal that stayed off
        ([0, 2000, 2000, 0], (0.0, 4000.0)),  # spindle speed, r/min: never below 0, up to twice the span
        ([0, 8000], (0.0, 16000.0)),
        ([19.5, 23.768], (7.0, 36.0)),  # ambient, degC: half its magnitude beyond the span
        ([20.0, 20.0], (10.0, 30.0)),
        ([-200.0, 300.0], (-700.0, 800.0)),  # an axis position: symmetric
        ([0.2, 0.7], (0.0, 2.0)),  # at least one unit, not below 0
        ([1e9, 3e9], (0.0, 5e9)),
        ([np.nan, np.inf], None),
    ],
)
def test_valid_range_of_a_source_column(values, expected):
    assert source_valid_range(values) == expected
    if expected is not None:
        assert all(float(np.float32(v)) == v for v in expected)  # exact in single precision


def test_large_ranges_round_outward_to_single_precision():
    low, high = source_valid_range([16_777_217.0, 16_777_219.0])
    assert low <= 16_777_217.0 - 8_388_609.5 and high >= 16_777_219.0 + 8_388_609.5
    assert float(np.float32(low)) == low and float(np.float32(high)) == high


def test_on_off_and_speed_readings_are_judged_on_their_own_scale():
    model, run = augmented_model("on/off p=1")
    section = model["switching"][SOURCE_RANGES_KEY]
    assert section["src_zscrew_on"] == [0.0, 1.0] and section["spindle_on"] == [0.0, 1.0]
    assert section["speed_rpm"] == [0.0, 4000.0]
    raw = readings(model, run)
    raw[50, 4], raw[60, 4], raw[70, 5], raw[80, 4] = 2.0, -1.0, 0.5, 1.0
    fault = SwitchingRule(model).replay(raw).fault
    assert fault[50] == FAULT_HELD and fault[60] == FAULT_HELD  # 2 and -1 are no on/off values
    assert fault[70] == 0 and fault[80] == 0


def test_model_files_carry_the_source_ranges_and_reload_to_the_same_rule(tmp_path):
    model, run = augmented_model("all kinds p=2")
    assert set(model["switching"][SOURCE_RANGES_KEY]) >= {"T_amb", "speed_rpm", "spindle_on", "T5", "T6"}
    assert "time_s" not in model["switching"][SOURCE_RANGES_KEY]
    assert "error_um" not in model["switching"][SOURCE_RANGES_KEY]
    write_model(model, tmp_path / "m.json")
    loaded = ModelFile.load(tmp_path / "m.json").to_dict()
    raw = readings(model, run)
    a, b = SwitchingRule(model).replay(raw), SwitchingRule(loaded).replay(raw)
    assert a.prediction_um.tobytes() == b.prediction_um.tobytes()


def test_power_stage_and_start_round_trip_through_the_model_file(tmp_path):
    model, run = augmented_model("heat law p=2")
    write_model(model, tmp_path / "m.json")
    text = (tmp_path / "m.json").read_text()
    entries = json.loads(text)["derived_inputs"]
    assert entries[0] == {**HEAT_LAW.to_dict(), "name": "(speed_rpm/1000)^1.667~lp1800sr"}
    assert entries[0]["exponent"] == 5 / 3 and entries[0]["scale"] == 1000.0 and entries[0]["start"] == "rest"
    assert "start" not in entries[1] and "exponent" not in entries[2]  # defaults are not written
    loaded = ModelFile.load(tmp_path / "m.json").to_dict()
    assert ModelFile.coerce(loaded).derived_inputs[0] == HEAT_LAW
    write_model(loaded, tmp_path / "again.json")
    assert (tmp_path / "again.json").read_text() == text
    raw = readings(model, run)
    a, b = SwitchingRule(model).replay(raw), SwitchingRule(loaded).replay(raw)
    assert a.prediction_um.tobytes() == b.prediction_um.tobytes()


def test_files_without_power_or_start_keys_load_unchanged(tmp_path):
    model, _ = augmented_model("all kinds p=2")
    assert not any({"exponent", "scale", "start"} & set(entry) for entry in model["derived_inputs"])
    write_model(model, tmp_path / "old.json")
    text = (tmp_path / "old.json").read_text()
    loaded = ModelFile.load(tmp_path / "old.json")
    assert all(f.exponent is None and f.scale is None and f.start == "steady" for f in loaded.derived_inputs)
    assert all(not d.has_power and not d.from_rest for d in RuleTables.from_model(loaded).derived)
    loaded.save(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_text() == text


def set_entry(**changes):
    def change(model):
        model["derived_inputs"][0].update(changes)

    return change


def drop_entry_key(key):
    def change(model):
        del model["derived_inputs"][0][key]

    return change


@pytest.mark.parametrize(
    "breakage, message",
    [
        (set_entry(exponent=0.0), r"derived_inputs\[0\]: exponent must be a finite number > 0, not 0.0"),
        (set_entry(exponent=-1.5), "exponent must be a finite number > 0"),
        (set_entry(exponent=float("nan")), "exponent must be a finite number > 0"),
        (set_entry(exponent="5/3"), "exponent must be a finite number > 0, not '5/3'"),
        (set_entry(exponent=True), "exponent must be a finite number > 0"),
        (set_entry(scale=float("inf")), "scale must be a finite number > 0"),
        (set_entry(scale=0), "scale must be a finite number > 0"),
        (drop_entry_key("exponent"), "needs both 'exponent' and 'scale'"),  # a scale without exponent
        (drop_entry_key("scale"), "needs both 'exponent' and 'scale'"),
        (set_entry(start="cold"), "start 'cold' must be one of steady, rest"),
        (set_entry(start=None), "start None must be one of steady, rest"),
        (set_entry(start="steady"), "name .* does not match its transform .*lp1800s'"),  # the name says rest
        (set_entry(exponent=2.0), "does not match its transform"),
    ],
)
def test_invalid_power_stages_and_starts_are_refused_in_one_line(tmp_path, breakage, message):
    model, _ = augmented_model("heat law p=2")
    breakage(model)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(model))
    with pytest.raises(InputError, match=message) as caught:
        ModelFile.load(path).to_dict()
    assert "\n" not in str(caught.value) and str(caught.value).startswith(str(path))


def test_older_files_without_source_ranges_or_rule_keys_still_load(tmp_path):
    model, run = augmented_model("all kinds p=2")
    raw = readings(model, run)
    full = SwitchingRule(model).replay(raw)
    del model["switching"][SOURCE_RANGES_KEY]
    write_model(model, tmp_path / "old.json")
    tables = RuleTables.from_model(ModelFile.load(tmp_path / "old.json").to_dict())
    assert tables.valid_origin[4:] == ("fallback",) * 3
    assert tables.valid_min[4:] == (LEGACY_SOURCE_RANGE[0],) * 3
    assert np.array_equal(SwitchingRule(model).replay(raw).prediction_um, full.prediction_um)
    for key in RULE_KEYS:
        del model["switching"][key]
    write_model(model, tmp_path / "older.json")
    older = SwitchingRule(ModelFile.load(tmp_path / "older.json").to_dict()).replay(raw)
    assert np.array_equal(older.group, full.group)
    assert np.max(np.abs(older.prediction_um - full.prediction_um)) <= 1e-9


def test_a_model_without_derived_inputs_reads_its_temperatures_only():
    model, run = augmented_model("lowpass p=0")
    model = copy.deepcopy(model)
    del model["derived_inputs"]
    model["temps"][4] = "T5"  # now a plain measured input
    tables = RuleTables.from_model(model)
    assert tables.raw_names == tables.input_names and tables.derived == ()
    assert tables.input_reading == tuple(range(5)) and tables.source_names == ()


def break_name(model):
    model["derived_inputs"][0]["name"] = "T_amb~lp60s"


def break_transform(model):
    model["derived_inputs"][0]["transform"] = "median"


def break_tau(model):
    model["derived_inputs"][0]["tau_s"] = -5.0


def break_delay(model):
    model["derived_inputs"][2]["delay_samples"] = 40000
    model["derived_inputs"][2]["name"] = "speed_rpm~delay40000"
    model["temps"][6] = "speed_rpm~delay40000"


def delay_a_lowpass(model):
    model["derived_inputs"][0]["delay_samples"] = -3


def break_criterion(model):
    model["switching"]["criterion_index"] = 4


def break_ranges(model):
    model["switching"][SOURCE_RANGES_KEY]["T_amb"] = [30.0, 10.0]


@pytest.mark.parametrize(
    "breakage, message",
    [
        (break_name, "does not match its transform"),
        (break_transform, "transform 'median'"),
        (break_tau, "tau_s > 0"),
        (break_delay, "at most 32767"),
        (delay_a_lowpass, "delay_samples = -3 belongs to a delay; leave it 0"),
        (break_criterion, "must be a measured input"),
        (break_ranges, "source_ranges\\['T_amb'\\]"),
    ],
)
def test_broken_derived_inputs_are_refused_on_loading(tmp_path, breakage, message):
    model, _ = augmented_model("all kinds p=2")
    breakage(model)
    write_model(model, tmp_path / "bad.json")
    with pytest.raises(InputError, match=message):
        ModelFile.load(tmp_path / "bad.json").to_dict()


@pytest.mark.parametrize("shift", [0, 2, -2])
def test_replay_groups_takes_the_model_inputs_as_diagnose_passes_them(shift):
    model, run = augmented_model("all kinds p=2")
    inputs = shifted(model_inputs(model, run), shift)
    raw = shifted(readings(model, run), shift)
    assert np.array_equal(replay_groups(model, inputs), SwitchingRule(model).replay(raw).group - 1)
    res = residual(model, run, live_rule=replay_groups)  # as groupfit diagnose scores with the live rule
    assert np.all(np.isfinite(res))


def test_single_precision_tracks_double_with_derived_inputs():
    model, run = augmented_model("all kinds p=2")
    raw = readings(model, run)
    double = SwitchingRule(model).replay(raw)
    single = SwitchingRule(model, precision="single").replay(raw)
    assert np.array_equal(single.group, double.group)
    assert np.max(np.abs(single.prediction_um - double.prediction_um)) < 1e-2
    assert single.prediction_um.tolist() == [float(np.float32(v)) for v in single.prediction_um]


def test_wrong_number_of_readings_names_them():
    model, run = augmented_model("lowpass p=0")
    with pytest.raises(InputError, match=r"the model takes 5 \(T1, T2, T3, T4, T_amb\)"):
        SwitchingRule(model).step([20.0] * 4)
