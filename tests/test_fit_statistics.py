"""``fit --p 0``: the regression's tests against statsmodels, the mean-response interval, backward elimination."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from scipy import stats

from groupfit.cli import main
from groupfit.models.mlr import MLR, backward_elimination


def synthetic_frame(seed: int = 0, n: int = 240) -> pd.DataFrame:
    """Error linear in T1 and T2 (rises over T_amb); T3 and T4 carry nothing but noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 60.0
    ambient = 20 + 0.5 * np.sin(t / 9000)
    rises = np.column_stack([8 * (1 - np.exp(-t / (2500 + 900 * j))) + rng.normal(0, 0.3, n) for j in range(4)])
    error = 1.5 + 2.0 * rises[:, 0] - 1.2 * rises[:, 1] + rng.normal(0, 0.4, n)
    frame = pd.DataFrame({"time_s": t, "T_amb": ambient, "error_um": error})
    for j in range(4):
        frame[f"T{j + 1}"] = ambient + rises[:, j]
    return frame


def relative(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


@pytest.mark.parametrize("intercept", [True, False])
def test_fit_p0_json_statistics_equal_statsmodels_ols(tmp_path, intercept):
    frame = synthetic_frame()
    csv = tmp_path / "run.csv"
    frame.to_csv(csv, index=False)
    options = [] if intercept else ["--no-intercept"]
    status = main(["fit", "--data", str(csv), "--p", "0", "--quiet", "--out", str(tmp_path / "out")]
                  + ["--json", str(tmp_path / "fit.json")] + options)  # fmt: skip
    assert status == 0
    stats = json.loads((tmp_path / "fit.json").read_text())["statistics"]
    rises = frame[["T1", "T2", "T3", "T4"]].to_numpy() - frame[["T_amb"]].to_numpy()  # fit's default reference
    design = sm.add_constant(rises) if intercept else rises
    ols = sm.OLS(frame["error_um"].to_numpy(), design).fit()
    assert [t["name"] for t in stats["terms"]] == (["const"] if intercept else []) + ["T1", "T2", "T3", "T4"]
    for key, truth in (("estimate", ols.params), ("std_error", ols.bse), ("t", ols.tvalues), ("p_value", ols.pvalues)):
        assert relative([t[key] for t in stats["terms"]], truth) < 1e-10
    assert relative(stats["f_value"], ols.fvalue) < 1e-10
    assert relative(stats["f_p_value"], ols.f_pvalue) < 1e-10 or stats["f_p_value"] == ols.f_pvalue == 0.0
    assert relative(stats["r_squared"], ols.rsquared) < 1e-10
    assert relative(stats["adjusted_r_squared"], ols.rsquared_adj) < 1e-10
    assert stats["f_dof"] == [ols.df_model, ols.df_resid]


def test_leverage_and_mean_interval_equal_statsmodels():
    frame = synthetic_frame(seed=1)
    X, y = frame[["T1", "T2", "T3"]].to_numpy(), frame["error_um"].to_numpy()
    model = MLR().fit(X, y)
    ols = sm.OLS(y, sm.add_constant(X)).fit()
    assert relative(model.leverage(X), ols.get_influence().hat_matrix_diag) < 1e-10
    new = X[::7] + 0.3
    for alpha in (0.05, 0.01):
        truth = ols.get_prediction(sm.add_constant(new, has_constant="add")).summary_frame(alpha=alpha)
        assert relative(model.mean_interval(new, alpha=alpha), truth[["mean_ci_lower", "mean_ci_upper"]]) < 1e-10


def test_backward_elimination_keeps_the_inputs_that_carry_the_error():
    frame = synthetic_frame(seed=2, n=400)
    rises = frame[["T1", "T2", "T3", "T4"]].to_numpy() - frame[["T_amb"]].to_numpy()
    chosen = backward_elimination(rises, frame["error_um"].to_numpy(), ["T1", "T2", "T3", "T4"], alpha=0.05)
    assert chosen["inputs"] == ["T1", "T2"]
    assert sorted(d["name"] for d in chosen["dropped"]) == ["T3", "T4"]
    # each round dropped the input with the largest p-value, computed here from the closed form of the t-test
    keep = [0, 1, 2, 3]
    for step in chosen["dropped"]:
        A = np.column_stack([np.ones(len(rises)), rises[:, keep]])
        coef, rss, *_ = np.linalg.lstsq(A, frame["error_um"].to_numpy(), rcond=None)
        dof = len(A) - A.shape[1]
        se = np.sqrt(rss[0] / dof * np.diag(np.linalg.inv(A.T @ A)))
        p = 2 * stats.t.sf(np.abs(coef / se), dof)[1:]
        worst = int(np.argmax(p))
        assert ["T1", "T2", "T3", "T4"][keep[worst]] == step["name"] and p[worst] > 0.05
        assert step["p_value"] == pytest.approx(p[worst], rel=1e-8)
        del keep[worst]


@pytest.mark.parametrize("copy_of", ["T1", "T1+T2"])
def test_backward_elimination_drops_an_input_in_a_linear_dependence_first(copy_of):
    """A sensor logged twice (or one the sum of others): statsmodels' t-tests on the rank-deficient design
    split one effect arbitrarily (a SingularMatrixWarning, nothing dropped); the dependent input goes first,
    and the rest is eliminated as on the design without it."""
    frame = synthetic_frame(seed=2, n=400)
    rises = frame[["T1", "T2", "T3", "T4"]].to_numpy() - frame[["T_amb"]].to_numpy()
    extra = rises[:, 0] if copy_of == "T1" else rises[:, 0] + rises[:, 1]
    names = ["T1", "T2", "T3", "T4", "T5"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning reaches the user
        chosen = backward_elimination(np.column_stack([rises, extra]), frame["error_um"].to_numpy(), names, alpha=0.05)
    first = chosen["dropped"][0]
    assert first["name"] == "T5" and first["t"] is None and set(first["dependent_on"]) == set(copy_of.split("+"))
    alone = backward_elimination(rises, frame["error_um"].to_numpy(), names[:4], alpha=0.05)
    assert chosen["inputs"] == alone["inputs"] and chosen["dropped"][1:] == alone["dropped"]


def test_backward_option_through_fit_and_its_errors(tmp_path, capsys):
    csv = tmp_path / "run.csv"
    synthetic_frame(seed=2, n=400).to_csv(csv, index=False)
    out = ["--quiet", "--out", str(tmp_path / "out")]
    assert (
        main(["fit", "--data", str(csv), "--p", "0", "--backward", "0.05", "--json", str(tmp_path / "f.json")] + out)
        == 0
    )
    result = json.loads((tmp_path / "f.json").read_text())
    assert result["temps"] == ["T1", "T2"] and result["input_selection"]["method"] == "backward"
    assert [t["name"] for t in result["statistics"]["terms"]] == ["const", "T1", "T2"]
    assert "backward elimination at alpha = 0.05: kept T1, T2 of 4" in capsys.readouterr().out
    assert main(["fit", "--data", str(csv), "--p", "2", "--backward", "0.05"] + out) == 2
    assert "--backward drops inputs of a global regression: use it with --p 0" in capsys.readouterr().err
    assert main(["fit", "--data", str(csv), "--p", "0", "--backward", "1.5"] + out) == 2
    assert "significance level 1.5" in capsys.readouterr().err
