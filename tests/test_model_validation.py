"""The model-file validator: a mutated model file is refused in one line, or it replays as the original does.

A model file is mutated field by field: a key deleted, or one value (at any
depth: ``breaks[1]``, ``switching.windows[0][1]``, ``coefficients[2][3]`` …)
replaced by a hostile value (another type, NaN, ±inf, ±1e308, −1) or, for a
whole number, shifted by one. Whatever the mutation, loading either refuses
it with one line (``InputError``; through the command line: exit 2, one
stderr line, no file written), or the model it gives makes the same
decisions as the original on the modelling run: the same group and the same
prediction at every sample. Nothing invalid is exported.

A different number in a free parameter (a coefficient, a clamp limit) is a
different valid model, not a corruption the file can reveal, so numbers are
only replaced by values no model holds (non-finite, huge, negative where a
sign is wrong) or, for the whole numbers that structure the model (p, n,
N, breaks, groups, windows, the criterion index), shifted by one.
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_switching_models import SYNTHETIC, augmented_model, readings, synthetic_model

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.model import COEFFICIENT_LIMIT, ModelFile
from groupfit.runtime import SwitchingRule

HOSTILE = [None, True, False, "text", [], {}, [1, 2], math.nan, math.inf, -math.inf, 1e308, -1e308, -1]
"""What a corrupted or hand-edited file may hold in place of any value."""
FREE = ("coefficients", "derived_inputs")
"""Sections whose whole numbers are free parameters (a delay of 4 samples instead of 3 is another valid model)."""
BLEND = ("switching", "blend_samples")
"""The bumpless transfer's length: a free parameter whose absence means a hard switch (tested on its own)."""


def _base():
    model, run = synthetic_model(p=3, n=3)
    return model, run.temps


def _paths(value, prefix=()):
    """Every path to a value in a JSON object (dict keys and list indices), the containers included."""
    yield prefix
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for k, item in enumerate(value[:6]):  # long series: their first entries stand for the rest
            yield from _paths(item, (*prefix, k))


def _get(obj, path):
    for key in path:
        obj = obj[key]
    return obj


def _set(obj, path, value):
    _get(obj, path[:-1])[path[-1]] = value


def _delete(obj, path):
    container = _get(obj, path[:-1])
    del container[path[-1]]


def mutations(model):
    """A strategy of (description, mutated model) pairs."""
    paths = [p for p in _paths(model) if p]

    @st.composite
    def one(draw):
        path = draw(st.sampled_from(paths))
        mutated = copy.deepcopy(model)
        current = _get(model, path)
        kinds = ["replace", "delete"]
        if path == BLEND:  # a free parameter; without it a file switches hard (a file written before it)
            kinds = ["replace"]
        elif isinstance(current, int) and not isinstance(current, bool) and path[0] not in FREE:
            kinds.append("shift")
        if path == ("temps",):
            kinds.append("duplicate")
        kind = draw(st.sampled_from(kinds))
        if kind == "replace":
            free = path[0] == "coefficients" and len(path) == 3  # any finite number is a valid coefficient
            a_range = path[:2] == ("switching", "source_ranges") and len(path) == 3  # [1, 2] is a valid range
            value = draw(
                st.sampled_from([v for v in HOSTILE if not (free and v == -1) and not (a_range and v == [1, 2])])
            )
            _set(mutated, path, value)
            label = f"{'.'.join(map(str, path))} = {value!r}"
        elif kind == "delete":
            _delete(mutated, path)
            label = f"delete {'.'.join(map(str, path))}"
        elif kind == "shift":
            step = draw(st.sampled_from([-1, 1]))
            _set(mutated, path, current + step)
            label = f"{'.'.join(map(str, path))} {step:+d}"
        else:
            mutated["temps"] = [*model["temps"][:-1], model["temps"][0]]
            label = "temps with a repeated name"
        return label, mutated

    return one()


def test_a_model_file_without_blend_samples_switches_hard():
    legacy = copy.deepcopy(BASE)
    del legacy["switching"]["blend_samples"]
    hard = copy.deepcopy(BASE)
    hard["switching"]["blend_samples"] = 0
    groups, prediction = decisions(ModelFile.from_dict(legacy), TEMPS)
    expected_groups, expected_prediction = decisions(ModelFile.from_dict(hard), TEMPS)
    assert np.array_equal(groups, expected_groups) and np.array_equal(prediction, expected_prediction)
    assert not np.array_equal(prediction, decisions(BASE, TEMPS)[1])  # the file's own transfer differs


def decisions(model, temps):
    replay = SwitchingRule(model).replay(temps)
    return replay.group.copy(), replay.prediction_um.copy()


def check_mutation(original, temps, label, mutated) -> str:
    """'refused' or 'identical'; AssertionError when a mutated model loads but decides differently."""
    try:
        model = ModelFile.from_dict(json.loads(json.dumps(mutated)))
        groups, prediction = decisions(model, temps)
    except InputError as exc:
        assert "\n" not in str(exc), label
        return "refused"
    expected_groups, expected_prediction = decisions(original, temps)
    assert np.array_equal(groups, expected_groups), f"{label}: loads but switches differently"
    assert np.array_equal(prediction, expected_prediction), f"{label}: loads but predicts differently"
    return "identical"


BASE, TEMPS = _base()


def _derived_base():
    model, run = augmented_model("heat law p=2")
    return model, readings(model, run)


DERIVED, DERIVED_READINGS = _derived_base()


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutations(BASE))
def test_a_mutated_model_is_refused_or_replays_identically(case):
    label, mutated = case
    check_mutation(BASE, TEMPS, label, mutated)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutations(DERIVED))
def test_a_mutated_model_with_derived_inputs_is_refused_or_replays_identically(case):
    label, mutated = case
    check_mutation(DERIVED, DERIVED_READINGS, label, mutated)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutations(DERIVED))
def test_fuzz_thousands_of_mutations_with_derived_inputs(case):
    label, mutated = case
    check_mutation(DERIVED, DERIVED_READINGS, label, mutated)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutations(BASE))
def test_fuzz_thousands_of_mutations(case):
    label, mutated = case
    check_mutation(BASE, TEMPS, label, mutated)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutations(BASE))
def test_through_the_command_line_exit_2_and_nothing_written_or_the_same_replay(tmp_path_factory, case):
    label, mutated = case
    folder = tmp_path_factory.mktemp("mutated")
    path = folder / "model.json"
    path.write_text(json.dumps(mutated), encoding="utf-8")
    result = folder / "replay.json"
    export = folder / "export"
    status = main(["replay", str(path), "--data", str(SYNTHETIC), "--json", str(result)])
    exported = main(["export", str(path), "--target", "all", "--out", str(export)])
    try:
        ModelFile.from_dict(json.loads(json.dumps(mutated)))
        valid = True
    except InputError:
        valid = False
    if not valid:
        assert status == 2 and exported == 2, label
        assert not result.exists() and not export.exists(), label
    else:
        assert exported == 0, label
        if status == 0:
            groups = [s["group"] for s in json.loads(result.read_text())["samples"]]
            assert np.array_equal(groups, decisions(BASE, TEMPS)[0]), label


CASES = {
    "breaks out of order": lambda m: m.update(breaks=[m["breaks"][1], m["breaks"][0], m["breaks"][2]]),
    "equal breaks": lambda m: m.update(breaks=[m["breaks"][0], m["breaks"][0], m["breaks"][2]]),
    "break beyond N": lambda m: m.update(breaks=[*m["breaks"][:2], m["n_samples"] + 5]),
    "negative n": lambda m: m.update(n=-1),
    "n larger than a hard group": lambda m: m.update(n=200),
    "windows reversed": lambda m: m["switching"].update(windows=[w[::-1] for w in m["switching"]["windows"]]),
    "windows moved": lambda m: m["switching"].update(windows=[[a + 5, b + 5] for a, b in m["switching"]["windows"]]),
    "negative period": lambda m: m.update(sampling_period_s=-100.0),
    "zero period": lambda m: m.update(sampling_period_s=0),
    "p as a string": lambda m: m.update(p="3"),
    "breaks a bare integer": lambda m: m.update(breaks=93),
    "breaks as floats": lambda m: m.update(breaks=[float(b) for b in m["breaks"]]),
    "huge coefficient": lambda m: m["coefficients"][1].__setitem__(2, 1e308),
    "coefficient over the limit": lambda m: m["coefficients"][0].__setitem__(1, 2 * COEFFICIENT_LIMIT),
    "non-string input name": lambda m: m["temps"].__setitem__(1, 7),
    "repeated input name": lambda m: m["temps"].__setitem__(1, "T1"),
    "p not the number of breaks": lambda m: m.update(p=2),
    "soft groups disagree": lambda m: m["soft_groups"][1].__setitem__(0, 10),
    "threshold disagrees": lambda m: m["switching"]["thresholds_c"].__setitem__(0, 99.0),
    "direction disagrees": lambda m: m["switching"]["directions"].__setitem__(0, -1),
    "criterion name disagrees": lambda m: m["switching"].update(criterion="T2"),
    "error is an input": lambda m: m.update(error="T1"),
    "error is an input, scaled": lambda m: m.update(error="T2*1000"),
    "error is the run's time": lambda m: m.update(
        error="time_s-start", training={**m.get("training", {}), "time": "time_s"}
    ),
    "error is the reference": lambda m: m.update(error="T_amb", reference="T_amb"),
    "reference 'none'": lambda m: m.update(reference="none"),
    "hard group not over-determined": lambda m: m.update(
        breaks=[3, *m["breaks"][1:]],
        n=0,
    ),
}


@pytest.mark.parametrize("label", list(CASES))
def test_each_invalid_model_is_refused_by_replay_and_export(tmp_path, capsys, label):
    model = copy.deepcopy(BASE)
    CASES[label](model)
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model), encoding="utf-8")
    with pytest.raises(InputError):
        ModelFile.from_dict(model)
    capsys.readouterr()
    for argv in (
        ["replay", str(path), "--data", str(SYNTHETIC), "--json", str(tmp_path / "r.json")],
        ["export", str(path), "--target", "all", "--out", str(tmp_path / "ex")],
    ):
        assert main(argv) == 2, (label, argv[0])
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "model.json" in err[0], err
    assert not (tmp_path / "r.json").exists() and not (tmp_path / "ex").exists()


def test_the_original_model_is_valid_and_saving_an_invalid_one_is_refused(tmp_path):
    model = ModelFile.from_dict(BASE)
    model.save(tmp_path / "ok.json")
    broken = model.replace(breaks=(model.breaks[1], model.breaks[0], model.breaks[2]))
    with pytest.raises(InputError, match="strictly increasing"):
        broken.save(tmp_path / "bad.json")
    assert not (tmp_path / "bad.json").exists()


def test_a_model_without_an_error_name_saves_and_exports_as_it_loads(tmp_path):
    """A required key holding null stays in the file: what loads also saves (a case the fuzzing found)."""
    data = json.loads(json.dumps(BASE))
    data["error"] = None
    model = ModelFile.from_dict(data)
    path = tmp_path / "model.json"
    model.save(path)
    assert json.loads(path.read_text())["error"] is None
    assert ModelFile.load(path) == model
    assert main(["export", str(path), "--target", "all", "--out", str(tmp_path / "export")]) == 0
