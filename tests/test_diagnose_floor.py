"""The least out-of-sample RMS an effect must remove: a lower floor for the first effect than for further ones.

Runs from the independent lumped machine (``bench/independent_machine.py``).
"""

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict
from support import independent_machine as machine
from support.bench_modules import load

from groupfit.diagnose import diagnose
from groupfit.diagnose.loop import MIN_EFFECT_RMS_UM, MIN_FURTHER_EFFECT_RMS_UM
from groupfit.features import derived_matrix
from groupfit.heldout.folds import make_folds
from groupfit.runtime import replay_groups

bench = load("bench_diagnose_independent")


def test_a_first_effect_between_the_two_floors_is_added_and_holds_on_the_next_run():
    # a part heated by the spindle with a 3 h lag: little of it shows on the modelling run, much on the next
    scenario = machine.random_scenarios(1, first_seed=38, truth="rises")[0]
    model, modelling, validation = bench.base_model(scenario, "default")
    result = diagnose(model, modelling, validation, live_rule=replay_groups)
    first = result.steps[0].candidate
    assert first.feature.column == "spindle_on"
    assert MIN_EFFECT_RMS_UM <= first.explained_rms_um < MIN_FURTHER_EFFECT_RMS_UM
    assert result.after["validate"]["rms_um"] < 0.6 * result.before["validate"]["rms_um"]

    # the RMS it removes out of sample, as scikit-learn's leave-one-group-out errors give it
    frame, y = modelling.frame, modelling.error
    groups = make_folds([frame], ["spindle_on"]).labels
    rises = frame[scenario.temps].to_numpy(float) - frame[["T_amb"]].to_numpy(float)
    effect = derived_matrix([first.feature], frame, model["sampling_period_s"])
    sse = [
        np.sum((y - cross_val_predict(LinearRegression(), X, y, groups=groups, cv=LeaveOneGroupOut())) ** 2)
        for X in (rises, np.c_[rises, effect])
    ]
    assert first.explained_rms_um == pytest.approx(np.sqrt((sse[0] - sse[1]) / len(y)), rel=1e-9)

    # held to the further effects' floor, it is left out and the model stays as it was
    strict = diagnose(
        model, modelling, validation, live_rule=replay_groups, min_effect_rms_um=MIN_FURTHER_EFFECT_RMS_UM
    )
    assert strict.added == [] and strict.after["validate"] == strict.before["validate"]


def test_further_effects_face_their_own_floor():
    scenario = machine.scenarios(["pump_45min_30s"])[0]
    model, modelling, validation = bench.base_model(scenario)
    both = diagnose(model, modelling, validation, live_rule=replay_groups)
    assert sorted(c.feature.column for c in both.added) == ["T_amb", "pump_on"]
    second = both.steps[1].candidate.explained_rms_um
    assert second >= MIN_FURTHER_EFFECT_RMS_UM
    first_only = diagnose(
        model, modelling, validation, live_rule=replay_groups, min_further_effect_rms_um=second * 1.01
    )
    assert [c.feature for c in first_only.added] == [both.added[0].feature]
