"""Held-out folds for a grouped model: a fold that takes a group's samples leaves nothing to fit it on."""

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from support.diagnose_scenarios import TEMPS, fit_model, lumped, sensor_error, with_ambient_effect

from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.heldout.folds import Folds
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.model import ModelFile


def test_a_grouped_design_is_scored_only_where_each_group_can_be_fitted():
    """The scorer's held-out SSE equals one regression per group on the other folds, on the scored samples."""
    rng = np.random.default_rng(3)
    n, floor = 240, 12
    groups = np.repeat([0, 1, 2], [100, 30, 110])  # group 1 lies inside fold 2 nearly whole
    labels = np.repeat(np.arange(6), 40)
    x = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    target = np.choose(groups, [x @ [1.0, -0.5], x @ [0.3, 0.8] + 2.0, x @ [-0.7, 0.2] - 1.0])
    target = target + rng.normal(scale=0.1, size=n)
    design = np.zeros((n, 9))
    for g in range(3):
        design[groups == g, 3 * g : 3 * g + 3] = np.column_stack([np.ones(n), x])[groups == g]
    folds = Folds(labels, "block").within_groups(groups, floor)

    expected, scored_rows = [], 0
    for label in range(6):
        held_out = labels == label
        squared = 0.0
        for g in np.unique(groups[held_out]):
            train, test = (groups == g) & ~held_out, (groups == g) & held_out
            if train.sum() <= floor:  # the group cannot be fitted without this fold
                assert not folds.scored[test].any()
                continue
            assert folds.scored[test].all()
            fitted = LinearRegression().fit(x[train], target[train])
            squared += float(np.sum((target[test] - fitted.predict(x[test])) ** 2))
            scored_rows += int(test.sum())
        if folds.scored[held_out].any():
            expected.append(squared)
    scorer = HeldOutScorer(target, design, folds)
    assert folds.n_unscored == n - scored_rows > 0
    np.testing.assert_allclose(scorer.base_sse, expected, rtol=1e-8)
    assert scorer.held_out_rms == pytest.approx(np.sqrt(sum(expected) / scored_rows))
    assert "samples not scored" in folds.describe()


@pytest.mark.parametrize("p", [2, 3])
def test_a_grouped_model_that_fits_is_not_called_over_fitted(tmp_path, p):
    """The error is the sensors' own: held out by condition, a grouped model predicts as well as in sample."""
    data_path, model_path = fit_model(tmp_path, sensor_error(lumped()), "clean", p=p)
    result = diagnose(ModelFile.load(model_path).to_dict(), load_run(data_path, temps=TEMPS))
    check = result.base_check
    assert not check.overfitted and check.held_out_rms_um < 1.5 * check.in_sample_rms_um
    assert not result.added and result.summary().startswith("nothing missing")


def test_a_missing_effect_is_found_on_a_grouped_model(tmp_path):
    data_path, model_path = fit_model(tmp_path, with_ambient_effect(lumped()), "ambient", p=2)
    result = diagnose(ModelFile.load(model_path).to_dict(), load_run(data_path, temps=TEMPS))
    assert not result.base_check.overfitted
    assert result.added and result.added[0].feature.column == "T_amb"
