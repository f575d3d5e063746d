"""GroupedRegressor with columns shared by every group, against one least-squares fit of the whole block design."""

import numpy as np
import pytest

from groupfit.errors import InputError
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.rewritten import with_slopes


def block_problem(seed=0, n_samples=240, breaks=(80, 170)):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_samples, 3)).cumsum(axis=0)
    groups = np.searchsorted(np.asarray(breaks), np.arange(1, n_samples + 1), side="left")
    own = np.array([[1.0, -0.4], [0.2, 0.9], [-0.7, 0.3]])[groups]
    y = (X[:, :2] * own).sum(axis=1) + 0.6 * X[:, 2] + np.array([0.0, 2.0, -1.0])[groups]
    return X, y + rng.normal(scale=0.05, size=n_samples), groups


@pytest.mark.parametrize("fit_intercept", [True, False])
def test_shared_column_has_the_joint_least_squares_coefficient(fit_intercept):
    X, y, groups = block_problem()
    # n = 0: soft groups are the hard ones, so the per-group refit on what the shared column leaves is the joint fit
    model = GroupedRegressor(n=0, c=0.0, fit_intercept=fit_intercept, fixed_breaks=[80, 170])
    model.set_params(shared_columns=[False, False, True]).fit(X, y)
    blocks = [np.column_stack([np.ones(len(X)), X[:, :2]]) if fit_intercept else X[:, :2]]
    width = blocks[0].shape[1]
    design = np.zeros((len(X), 3 * width))
    for g in range(3):
        design[groups == g, g * width : (g + 1) * width] = blocks[0][groups == g]
    joint = np.linalg.lstsq(np.column_stack([design, X[:, 2]]), y, rcond=None)[0]
    per_group = joint[:-1].reshape(3, width)
    assert model.coef_[:, 2] == pytest.approx(np.full(3, joint[-1]), rel=1e-9)
    assert model.coef_[:, :2] == pytest.approx(per_group[:, int(fit_intercept) :], rel=1e-8, abs=1e-10)
    if fit_intercept:
        assert model.intercept_ == pytest.approx(per_group[:, 0], rel=1e-8, abs=1e-10)
    assert model.interval_stats_ is None and model.n_features_in_ == 3
    assert model.residuals_ == pytest.approx(y - model.predict(X), abs=1e-9)


def test_without_breaks_or_shared_columns_the_fit_is_the_plain_one():
    X, y, _ = block_problem(seed=1)
    plain = GroupedRegressor(n=0, c=0.0, fixed_breaks=[]).fit(X, y)
    shared = GroupedRegressor(n=0, c=0.0, fixed_breaks=[], shared_columns=[False, False, True]).fit(X, y)
    assert np.array_equal(plain.coef_, shared.coef_) and shared.interval_stats_ is not None


def test_a_mask_of_the_wrong_length_is_refused():
    X, y, _ = block_problem(seed=2)
    with pytest.raises(InputError, match="shared_columns marks 2 columns; X has 3"):
        GroupedRegressor(n=0, c=0.0, fixed_breaks=[80, 170], shared_columns=[True, False]).fit(X, y)


def test_with_slopes_writes_the_same_model_on_other_inputs_and_leaves_the_fit_alone():
    X, y, _ = block_problem(seed=3)
    # inputs as rises over the third column, written on absolute readings: T_i − R → T_i and R with −Σ slopes
    rises = X[:, :2] - X[:, [2]]
    on_rises = GroupedRegressor(n=3, c=0.0, fixed_breaks=[80, 170]).fit(rises, y)
    slopes = on_rises.coef_.copy()
    absolute = with_slopes(on_rises, np.column_stack([slopes, -slopes.sum(axis=1)]))
    assert absolute.predict(X) == pytest.approx(on_rises.predict(rises), abs=1e-9)
    assert np.array_equal(on_rises.coef_, slopes) and on_rises.n_features_in_ == 2
    assert absolute.interval_stats_ is None and on_rises.interval_stats_ is not None
