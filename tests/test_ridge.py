"""The ridge penalty for a global model on many collinear inputs: fit, held-out scoring, CLI, diagnosis."""

import json

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import Ridge

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.fast_response import without_stage
from groupfit.heldout.expect import expect_next_run
from groupfit.heldout.folds import Folds, make_folds
from groupfit.heldout.penalty import penalised_expectation, penalty_lines
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.model import ModelFile, model_file_problem
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.ridge import choose_ridge_alpha, held_out_sse
from groupfit.runtime import replay_groups

SENSORS = [f"T{k}" for k in range(1, 13)]


def copies_run(seed, n=80):
    """Twelve noisy sensors that all see one heated part, and an error that follows the part."""
    rng = np.random.default_rng(seed)
    on = np.repeat(rng.permutation([0, 1, 0, 1, 0, 1, 0, 1]), n // 8).astype(float)
    part = np.zeros(n)
    for i in range(1, n):
        part[i] = part[i - 1] + (5.0 * on[i] - part[i - 1]) * 0.05
    frame = pd.DataFrame({"time_s": np.arange(n) * 60.0, "spindle_on": on})
    for k, name in enumerate(SENSORS, start=1):
        frame[name] = 20.0 + part * (0.5 + 0.1 * k) + rng.normal(scale=0.6, size=n)
    frame["error_um"] = 3.0 * part + rng.normal(scale=0.2, size=n)
    return frame


def collinear(seed=0, n=200, k=5):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, k)) @ rng.normal(size=(k, k)) + 3.0
    return X, X @ rng.normal(size=k) + rng.normal(size=n)


@pytest.mark.parametrize("intercept", [True, False])
@pytest.mark.parametrize("alpha", [0.0, 0.01, 0.3])
def test_ridge_coefficients_equal_scikit_learn_on_unit_spread_inputs(alpha, intercept):
    X, y = collinear()
    fitted = GroupedRegressor(p=0, c=0, ridge_alpha=alpha, fit_intercept=intercept).fit(X, y)
    spread = X.std(axis=0) if intercept else np.sqrt(np.mean(X**2, axis=0))
    peer = Ridge(alpha=alpha * len(y), fit_intercept=intercept, solver="cholesky").fit(X / spread, y)
    np.testing.assert_allclose(fitted.coef_[0], peer.coef_ / spread, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(fitted.predict(X), peer.predict(X / spread), atol=1e-8)


def test_held_out_scoring_with_ridge_equals_a_ridge_refit_on_every_fold():
    X, y = collinear(seed=3, n=300, k=4)
    rng = np.random.default_rng(4)
    candidate = np.cumsum(rng.normal(size=len(y)))
    y = y + 0.5 * candidate
    folds = Folds(np.repeat(np.arange(5), len(y) // 5), "block")
    alpha = 0.02
    design = np.column_stack([np.ones(len(y)), X])
    scorer = HeldOutScorer(y, design, folds, ridge_alpha=alpha)
    augmented = np.column_stack([X, candidate])
    spread = augmented.std(axis=0)  # of all samples: one fixed penalty, refitted per fold
    base, with_candidate = [], []
    for train, test in folds.splits():
        for columns, out in ((slice(0, 4), base), (slice(0, 5), with_candidate)):
            Z = augmented[:, columns] / spread[columns]
            peer = Ridge(alpha=alpha * train.sum(), solver="cholesky").fit(Z[train], y[train])
            out.append(np.sum((y[test] - peer.predict(Z[test])) ** 2))
    np.testing.assert_allclose(scorer.base_sse, base, rtol=1e-8)
    np.testing.assert_allclose(scorer.fold_sse(candidate), with_candidate, rtol=1e-8)
    np.testing.assert_allclose(held_out_sse(X, y, list(folds.index_splits()), alpha), base, rtol=1e-8)
    everything = Ridge(alpha=alpha * len(y), solver="cholesky").fit(augmented / spread, y)
    assert scorer.coefficient(candidate) * np.linalg.norm(design, axis=0)[0] == pytest.approx(
        everything.coef_[-1] / spread[-1] * np.linalg.norm(design, axis=0)[0], rel=1e-8
    )


def test_ridge_chosen_on_held_out_conditions_predicts_the_next_run_better_than_least_squares():
    gains = []
    for seed in range(5):
        modelling, other = copies_run(seed), copies_run(seed + 10)
        X, y = modelling[SENSORS].to_numpy(), modelling["error_um"].to_numpy()
        splits = make_folds([modelling], ["spindle_on"]).index_splits()
        alpha, table = choose_ridge_alpha(X, y, splits)
        assert alpha > 0 and alpha == min(table, key=lambda row: row["held_out_rms_um"])["alpha"]
        rms = {}
        for name, penalty in (("ls", 0.0), ("ridge", alpha)):
            fitted = GroupedRegressor(p=0, c=0, ridge_alpha=penalty).fit(X, y)
            rms[name] = np.sqrt(np.mean((fitted.predict(other[SENSORS].to_numpy()) - other["error_um"]) ** 2))
        assert rms["ridge"] <= rms["ls"] * 1.001
        gains.append(1.0 - rms["ridge"] / rms["ls"])
    assert np.mean(gains) > 0.02


def test_fit_ridge_auto_writes_the_penalty_and_the_model_runs_unchanged(tmp_path, capsys):
    path = tmp_path / "run.csv"
    copies_run(1).to_csv(path, index=False)
    out = tmp_path / "model"
    args = ["fit", "--data", str(path), "--temps", ",".join(SENSORS), "--p", "0", "--ridge", "auto"]
    assert main([*args, "--reference", "none", "--out", str(out), "--json", "-", "--quiet"]) == 0
    result = json.loads(capsys.readouterr().out)
    ridge = result["ridge"]
    frame = copies_run(1)
    splits = make_folds([frame], ["spindle_on"]).index_splits()  # one fold per stretch of spindle_on
    alpha, table = choose_ridge_alpha(frame[SENSORS].to_numpy(), frame["error_um"].to_numpy(), splits)
    assert ridge["chosen"] == "held-out" and "leave-one-condition-out" in ridge["folds"]
    assert ridge["alpha"] == alpha > 0 and not ridge["default"]
    assert [row["held_out_rms_um"] for row in ridge["held_out"]] == pytest.approx(
        [row["held_out_rms_um"] for row in table]
    )
    model = ModelFile.load(out / "model.json")
    assert model.ridge_alpha == ridge["alpha"]
    peer = GroupedRegressor(p=0, c=0, ridge_alpha=ridge["alpha"]).fit(frame[SENSORS], frame["error_um"])
    np.testing.assert_allclose(model.coefficients[0], [peer.intercept_[0], *peer.coef_[0]], rtol=1e-9)
    replayed = replay_groups(model.to_dict(), frame[SENSORS].to_numpy())
    prediction = model.predict(frame[SENSORS].to_numpy(), replayed)
    np.testing.assert_allclose(prediction, peer.predict(frame[SENSORS]), atol=1e-9)


def test_fit_gives_the_global_model_it_chooses_the_penalty_that_holds_on_another_day(tmp_path, capsys):
    """With p chosen (no --p, no --ridge) and p = 0 chosen, fit applies --ridge auto; --ridge 0 and --p 0 stay
    least squares. The penalised model predicts other days of the same machine better (truth by construction)."""
    path = tmp_path / "run.csv"
    frame = copies_run(4)
    frame.to_csv(path, index=False)
    base = ["fit", "--data", str(path), "--temps", ",".join(SENSORS), "--reference", "none"]
    results = {}
    for name, extra in (("default", []), ("ridge 0", ["--ridge", "0"]), ("p 0", ["--p", "0"])):
        out = tmp_path / name.replace(" ", "")
        assert main([*base, *extra, "--out", str(out), "--json", "-", "--quiet"]) == 0
        results[name] = (json.loads(capsys.readouterr().out), ModelFile.load(out / "model.json"))
    result, model = results["default"]
    assert result["breaks"] == [] and result["ridge"]["default"] is True
    splits = make_folds([frame], ["spindle_on"]).index_splits()
    alpha, _ = choose_ridge_alpha(frame[SENSORS].to_numpy(), frame["error_um"].to_numpy(), splits)
    assert model.ridge_alpha == result["ridge"]["alpha"] == alpha > 0
    assert "statistics" not in result  # the t-tests of least squares do not describe a penalised fit
    assert result["expected_next_run_rms_um"] == pytest.approx(model.training["expected_next_run_rms_um"])
    assert model.training["model_choice"]["p"] == 0
    for name in ("ridge 0", "p 0"):
        assert results[name][1].ridge_alpha is None and "statistics" in results[name][0]
    least_squares = results["p 0"][1]
    np.testing.assert_allclose(results["ridge 0"][1].coefficients, least_squares.coefficients, rtol=1e-9)
    rms = {"ridge": [], "ls": []}
    for seed in range(20, 25):
        other = copies_run(seed)
        for key, fitted in (("ridge", model), ("ls", least_squares)):
            prediction = fitted.predict(other[SENSORS].to_numpy(), np.zeros(len(other), dtype=int))
            rms[key].append(np.sqrt(np.mean((other["error_um"] - prediction) ** 2)))
    assert np.mean(rms["ridge"]) < np.mean(rms["ls"])


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--p", "2", "--ridge", "0.1"], "--ridge with p = 2"),
        (["--p", "0", "--ridge", "-1"], "invalid penalty"),
        (["--p", "0", "--ridge", "lots"], "invalid penalty"),
    ],
)
def test_fit_ridge_refuses_what_it_cannot_do_in_one_line(tmp_path, capsys, extra, message):
    path = tmp_path / "run.csv"
    copies_run(2, n=400).to_csv(path, index=False)
    out = tmp_path / "model"
    args = ["fit", "--data", str(path), "--temps", ",".join(SENSORS[:3]), *extra, "--out", str(out), "--quiet"]
    try:
        code = main(args)
    except SystemExit as exc:  # argparse usage errors
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[-1]
    assert not out.exists()


def test_model_file_ridge_alpha_is_checked():
    X, y = collinear()
    frame = pd.DataFrame(X, columns=[f"x{k}" for k in range(X.shape[1])])
    frame.insert(0, "time_s", np.arange(len(y)) * 10.0)
    frame["error_um"] = y
    run = load_run(frame, temps=list(frame.columns[1:-1]))
    model = GroupedRegressor(p=0, c=0, ridge_alpha=0.1).fit(run.temps, run.error).to_model_file(run).to_dict()
    assert model_file_problem(model) is None and model["ridge_alpha"] == 0.1
    assert "ridge_alpha = -1" in model_file_problem({**model, "ridge_alpha": -1})
    assert "ridge_alpha = 'x'" in model_file_problem({**model, "ridge_alpha": "x"})
    grouped = GroupedRegressor(p=1, c=0).fit(run.temps, run.error).to_model_file(run).to_dict()
    assert "belongs to a global model" in model_file_problem({**grouped, "ridge_alpha": 0.1})


def test_diagnose_with_ridge_scores_and_refits_with_the_same_penalty(tmp_path, capsys):
    frame = copies_run(3, n=400)
    hours = frame["time_s"].to_numpy() / 3600.0
    frame["T_amb"] = 20.0 + 2.0 * np.sin(2 * np.pi * hours / 3.0)
    frame["error_um"] += 1.5 * (frame["T_amb"] - 20.0)
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    model_dir = tmp_path / "model"
    args = ["fit", "--data", str(path), "--temps", ",".join(SENSORS), "--p", "0", "--reference", "none"]
    assert main([*args, "--out", str(model_dir), "--quiet"]) == 0
    capsys.readouterr()
    args = ["diagnose", str(model_dir / "model.json"), "--data", str(path), "--ridge", "0.01"]
    assert main([*args, "--out", str(tmp_path / "d"), "--json", str(tmp_path / "d.json")]) == 0
    report = capsys.readouterr().out.splitlines()
    result = json.loads((tmp_path / "d.json").read_text())
    assert report[0].startswith("coefficients refitted with the ridge penalty alpha = 0.01 (given)")
    assert result["ridge"] == {"alpha": 0.01, "chosen": "given"} and result["added"][0]["column"] == "T_amb"
    given = json.loads((model_dir / "model.json").read_text())
    assert result["before"]["data"]["rms_um"] == pytest.approx(given["training"]["rms_um"])
    augmented = without_stage(ModelFile.load(tmp_path / "d" / "model_augmented.json"))  # the model itself
    assert augmented.ridge_alpha == 0.01
    feature = augmented.derived_inputs[0]
    X = np.column_stack([frame[SENSORS], feature.compute(frame["T_amb"].to_numpy(), 60.0)])
    spread = X.std(axis=0)
    peer = Ridge(alpha=0.01 * len(X), solver="cholesky").fit(X / spread, frame["error_um"])
    np.testing.assert_allclose(augmented.coefficients[0][1:], peer.coef_ / spread, rtol=1e-7)


def test_compare_reports_the_penalty_fit_gives_its_global_model():
    frame = copies_run(4)
    run = load_run(frame, temps=SENSORS)
    penalty = penalised_expectation(run)
    splits = make_folds([frame], ["spindle_on"]).index_splits()
    alpha, _ = choose_ridge_alpha(frame[SENSORS].to_numpy(), frame["error_um"].to_numpy(), splits)
    assert penalty["alpha"] == alpha > 0
    expected = expect_next_run([run], (0,), ridge_alpha=alpha).expected()[0]
    assert penalty["expected_next_run_rms_um"] == pytest.approx(expected)
    assert expected != pytest.approx(expect_next_run([run], (0,)).expected()[0])
    assert f"alpha = {alpha:g}" in penalty_lines(penalty)[0]
    assert penalty_lines({**penalty, "alpha": 0.0}) == [] and penalty_lines(None) == []


def test_several_runs_get_the_penalty_with_the_least_error_on_the_held_out_runs(tmp_path, capsys):
    frames = [copies_run(seed) for seed in (5, 6, 7)]
    paths = []
    for k, frame in enumerate(frames):
        paths.append(str(tmp_path / f"run{k}.csv"))
        frame.to_csv(paths[-1], index=False)
    args = ["fit", "--data", *paths, "--temps", ",".join(SENSORS), "--reference", "none", "--recalibrate", "none"]
    assert main([*args, "--out", str(tmp_path / "m"), "--json", "-", "--quiet"]) == 0
    result = json.loads(capsys.readouterr().out)
    X = np.vstack([f[SENSORS].to_numpy() for f in frames])
    y = np.concatenate([f["error_um"].to_numpy() for f in frames])
    rows = np.arange(len(y))
    splits = [(rows[(rows // 80) != k], rows[(rows // 80) == k]) for k in range(3)]  # each run held out once
    alpha, _ = choose_ridge_alpha(X, y, splits)
    assert result["ridge"]["alpha"] == alpha > 0 and result["ridge"]["default"] is True
    assert "leave-one-run-out over 3 runs" in result["ridge"]["folds"]
    assert "leave-one-run-out over 3 runs" in result["expected_next_run_method"]
