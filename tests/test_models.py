import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone
from sklearn.linear_model import LinearRegression

from groupfit.grouping import Constraints
from groupfit.models import MLR, GroupedRegressor
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact


def test_mlr_matches_scikit_learn(lumped_run):
    X, y = lumped_run
    mlr = MLR().fit(X, y)
    reference = LinearRegression().fit(X, y)
    np.testing.assert_allclose(mlr.coef_[0], reference.coef_, rtol=1e-7)
    assert mlr.intercept_[0] == pytest.approx(reference.intercept_, rel=1e-7)
    assert mlr.objective_value_ == pytest.approx(np.sum(np.abs(y - reference.predict(X))), rel=1e-9)
    assert mlr.score(X, y) == pytest.approx(reference.score(X, y), rel=1e-12)
    p0 = GroupedRegressor(p=0).fit(X, y)
    np.testing.assert_allclose(p0.coef_, mlr.coef_)


def test_exact_fit_groups_are_least_squares_on_their_soft_groups(lumped_run):
    X, y = lumped_run
    model = GroupedRegressor(p=3, search="exact").fit(X, y)
    exact = solve_exact(SegmentCost(X, y, n=3), Constraints.for_model(len(y), 3, 3.0, 5), 3)
    assert model.breaks_ == exact.breaks[3]
    assert model.objective_value_ == pytest.approx(exact.objective[3], rel=1e-9)
    A = np.column_stack([np.ones(len(y)), X])
    for g, (first, last) in enumerate(model.soft_groups_):
        reference = np.linalg.lstsq(A[first - 1 : last], y[first - 1 : last], rcond=None)[0]
        assert model.intercept_[g] == pytest.approx(reference[0], rel=1e-6, abs=1e-6)
        np.testing.assert_allclose(model.coef_[g], reference[1:], rtol=1e-6)
    np.testing.assert_allclose(model.predict(X), y - model.residuals_, atol=1e-9)
    assert np.sum(np.abs(model.residuals_)) == pytest.approx(model.objective_value_, rel=1e-12)


def test_ga_fit_is_certified_when_cheap(lumped_run):
    X, y = lumped_run
    model = GroupedRegressor(p=2, random_state=3).fit(X, y)
    search = model.search_
    assert search["method"] == "ga" and search["seed"] == 3
    assert search["gap_percent"] >= -1e-9
    assert search["exact_objective"] == pytest.approx(GroupedRegressor(p=2, search="exact").fit(X, y).objective_value_)


def test_grouping_beats_one_regression_on_a_changing_mapping(lumped_run):
    X, y = lumped_run
    values = [GroupedRegressor(p=p, search="exact").fit(X, y).objective_value_ for p in range(4)]
    assert values[0] == pytest.approx(MLR().fit(X, y).objective_value_)
    assert values[3] < 0.6 * values[0]


def test_predict_by_sample_index_and_past_the_run(lumped_run):
    X, y = lumped_run
    model = GroupedRegressor(p=2, search="exact").fit(X, y)
    longer = np.vstack([X, X[-10:]])
    prediction = model.predict(longer)
    np.testing.assert_allclose(prediction[-10:], model.intercept_[-1] + X[-10:] @ model.coef_[-1])
    np.testing.assert_allclose(prediction[: len(y)], model.predict(X))


def test_estimator_api_conventions(lumped_run):
    X, y = lumped_run
    model = GroupedRegressor(p=2, n=2, c=2.5, objective="sse", search="exact")
    assert clone(model).get_params() == model.get_params()
    frame = pd.DataFrame(X, columns=["T1", "T2", "T3", "T4"])
    fitted = model.fit(frame, y)
    assert list(fitted.feature_names_in_) == ["T1", "T2", "T3", "T4"]
    assert fitted.n_features_in_ == 4 and fitted.n_samples_fit_ == len(y)
    assert not hasattr(clone(model), "breaks_")
    no_intercept = GroupedRegressor(p=1, fit_intercept=False, search="exact").fit(X, y)
    assert np.all(no_intercept.intercept_ == 0.0) and no_intercept.n_coef == 4


ORDER_DEPENDENT = "a grouped model serves row i with the group of sample i: its prediction follows the time order"


@pytest.mark.parametrize(
    "estimator, expected_failures",
    [
        (MLR(), {}),
        (GroupedRegressor(p=0, c=0.0), {}),
        (
            GroupedRegressor(p=1, n=0, c=0.0, random_state=0),
            {
                "check_methods_sample_order_invariance": ORDER_DEPENDENT,
                "check_methods_subset_invariance": ORDER_DEPENDENT,
                "check_regressors_no_decision_function": "10 samples of 4 features: two groups of more than "
                "M = 5 samples each do not fit (every group stays over-determined, whatever c)",
            },
        ),
    ],
    ids=["MLR", "grouped p=0", "grouped p=1"],
)
@pytest.mark.slow
def test_estimators_pass_scikit_learns_checks(estimator, expected_failures):
    import sklearn
    from sklearn.utils.estimator_checks import check_estimator

    if tuple(int(v) for v in sklearn.__version__.split(".")[:2]) < (1, 6):
        pytest.skip("expected_failed_checks needs scikit-learn 1.6")
    results = check_estimator(estimator, on_fail=None, expected_failed_checks=expected_failures)
    failed = [r["check_name"] for r in results if r["status"] == "failed"]
    assert failed == []
