"""Inputs and effects chosen together (``diagnose --select joint``), checked against scikit-learn's cross-validation."""

import json

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict
from support.diagnose_scenarios import SPINDLE_PERIOD_S, SPINDLE_SENSORS, spindle_run

from groupfit.cli import main
from groupfit.diagnose.joint import JointProblem
from groupfit.diagnose.policy import AcceptancePolicy
from groupfit.features import Feature
from groupfit.heldout.folds import make_folds
from groupfit.heldout.selection import MIN_GAIN

PERIOD = SPINDLE_PERIOD_S
SENSORS = SPINDLE_SENSORS
SHARE_ONLY = AcceptancePolicy(
    min_score=0.3, min_effect_rms_um=0.0, min_folds_improved=-1.0, max_fold_worsening=np.inf, collinear_r=np.inf
)
"""A policy that tests an effect's share of the held-out error and nothing else (the reference below does)."""


def heat_law(tau):
    return Feature("speed_rpm", "lowpass", tau_s=tau, exponent=5 / 3, scale=1000.0, start="rest")


def explicit_forward(X, y, groups, n_inputs, min_score):
    """Forward selection scored by scikit-learn's leave-one-group-out predictions (columns < n_inputs: inputs)."""
    chosen, remaining = [], list(range(X.shape[1]))

    def sse(columns):
        if not columns:
            predicted = cross_val_predict(
                LinearRegression(), np.ones((len(y), 1)), y, groups=groups, cv=LeaveOneGroupOut()
            )
        else:
            predicted = cross_val_predict(LinearRegression(), X[:, columns], y, groups=groups, cv=LeaveOneGroupOut())
        return float(np.sum((y - predicted) ** 2))

    current = sse(chosen)
    while True:
        scores = {c: 1.0 - sse(chosen + [c]) / current for c in remaining}
        eligible = {c: s for c, s in scores.items() if s >= (MIN_GAIN if c < n_inputs else min_score)}
        if not eligible:
            return chosen
        best = max(eligible, key=eligible.get)
        chosen.append(best)
        remaining.remove(best)
        if best >= n_inputs:  # one effect per column: the others are lags of the same column
            remaining = [c for c in remaining if c < n_inputs]
        current = sse(chosen)


def test_joint_selection_is_the_forward_search_scikit_learn_scores():
    frame = spindle_run(1)
    y = frame["error_um"].to_numpy()
    taus = (1200.0, 3600.0, 7200.0, 14400.0)
    effects = [(heat_law(t), heat_law(t).compute(frame["speed_rpm"].to_numpy(), PERIOD)) for t in taus]
    rng = np.random.default_rng(0)
    walk = 20.0 + np.cumsum(rng.normal(scale=0.01, size=len(frame)))  # sensors that carry nothing of the error
    inputs = {"T1": frame["T1"].to_numpy(), "walk": walk, "noise": rng.normal(size=len(frame))}
    folds = make_folds([frame], ["speed_rpm"])
    chosen = JointProblem(y, inputs, effects, folds, SHARE_ONLY, 0 * y).select()

    X = np.column_stack([*inputs.values(), *(v for _, v in effects)])
    names = [*inputs, *(f.name for f, _ in effects)]
    expected = [names[c] for c in explicit_forward(X, y, folds.labels, len(inputs), 0.3)]
    assert chosen.order == expected
    assert chosen.order[:2] in (["T1", heat_law(7200.0).name], [heat_law(7200.0).name, "T1"])
    # the held-out RMS it reports after each step is scikit-learn's leave-one-group-out RMS of that model
    columns = [names.index(n) for n in chosen.order]
    last = cross_val_predict(LinearRegression(), X[:, columns], y, groups=folds.labels, cv=LeaveOneGroupOut())
    assert chosen.held_out_rms[-1] == pytest.approx(np.sqrt(np.mean((y - last) ** 2)), rel=1e-9)


def test_nested_error_predicts_each_condition_with_a_selection_made_without_it():
    frame = spindle_run(2)
    y = frame["error_um"].to_numpy()
    effects = [(heat_law(7200.0), heat_law(7200.0).compute(frame["speed_rpm"].to_numpy(), PERIOD))]
    inputs = {"T1": frame["T1"].to_numpy()}
    folds = make_folds([frame], ["speed_rpm"])
    problem = JointProblem(y, inputs, effects, folds, SHARE_ONLY, 0 * y)
    for train, _ in folds.splits():  # both columns are chosen without any one condition ...
        assert sorted(problem.restricted(train).select().order) == sorted(["T1", heat_law(7200.0).name])
    # ... so the nested error is scikit-learn's leave-one-group-out error of those two columns
    X = np.column_stack([inputs["T1"], effects[0][1]])
    predicted = cross_val_predict(LinearRegression(), X, y, groups=folds.labels, cv=LeaveOneGroupOut())
    expected = np.sqrt(np.mean((y - predicted) ** 2))
    assert problem.nested_held_out_rms() == pytest.approx(expected, rel=1e-9)


def fit_all_sensors(tmp_path, frame):
    path = tmp_path / "modelling.csv"
    frame.to_csv(path, index=False)
    args = ["fit", "--data", str(path), "--temps", ",".join(SENSORS), "--p", "0", "--reference", "none"]
    assert main([*args, "--quiet", "--out", str(tmp_path / "m")]) == 0
    return path, tmp_path / "m" / "model.json"


def test_diagnose_select_joint_keeps_one_sensor_and_names_the_speed(tmp_path, capsys):
    path, model = fit_all_sensors(tmp_path, spindle_run(3))
    validation = tmp_path / "validation.csv"
    spindle_run(4).to_csv(validation, index=False)
    capsys.readouterr()
    args = ["diagnose", str(model), "--data", str(path), "--validate", str(validation), "--select", "joint"]
    assert main([*args, "--out", str(tmp_path / "d"), "--json", str(tmp_path / "d.json")]) == 0
    report = capsys.readouterr().out.splitlines()
    result = json.loads((tmp_path / "d.json").read_text())
    assert report[0].startswith("inputs re-selected together with the effects on held-out conditions")
    assert len(result["selection"]["inputs"]) < len(SENSORS)
    assert result["added"][0]["column"] == "speed_rpm" and result["added"][0]["exponent"] == pytest.approx(5 / 3)
    assert any(line.startswith("effect chosen with the inputs: spindle speed") for line in report)
    assert result["steps"][0]["joint"] is True and "against the inputs chosen before it" in "\n".join(report)
    # the procedure's own forecast for a new condition beats the given model's, and the next run agrees
    assert result["selection"]["nested_held_out_rms_um"] < result["base_model"]["held_out_rms_um"]
    before, after = result["before"]["validate"]["rms_um"], result["after"]["validate"]["rms_um"]
    assert result["improved"] is True and after < 0.6 * before
    augmented = json.loads((tmp_path / "d" / "model_augmented.json").read_text())
    assert augmented["temps"][: len(result["selection"]["inputs"])] == result["selection"]["inputs"]
    # the switching criterion is a measured input that was kept (the given one, or the kept input moving most)
    assert augmented["switching"]["criterion"] in result["selection"]["inputs"]
    # the model written replays like any other
    assert main(["replay", str(tmp_path / "d" / "model_augmented.json"), "--data", str(validation)]) == 0


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--ridge", "auto"], "--select joint and --ridge: the joint selection fits by least squares"),
        (["--p", "1"], "--select joint re-chooses the inputs of a global model (p = 0)"),
    ],
)
def test_diagnose_select_joint_refuses_what_it_cannot_do(tmp_path, capsys, extra, message):
    frame = spindle_run(5, hours=8.0)
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    p = extra[1] if extra[0] == "--p" else "0"
    args = ["fit", "--data", str(path), "--temps", "T1,T2", "--p", p, "--reference", "none", "--quiet"]
    if p != "0":
        args += ["--n", "2", "--c", "2"]
    assert main([*args, "--out", str(tmp_path / "m")]) == 0
    capsys.readouterr()
    diagnose_args = ["diagnose", str(tmp_path / "m" / "model.json"), "--data", str(path), "--select", "joint"]
    if extra[0] == "--ridge":
        diagnose_args += extra
    assert main([*diagnose_args, "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not (tmp_path / "d").exists()


def test_diagnose_select_joint_refuses_a_model_with_derived_inputs(tmp_path, capsys):
    path, model = fit_all_sensors(tmp_path, spindle_run(6, hours=10.0))
    assert main(["diagnose", str(model), "--data", str(path), "--out", str(tmp_path / "first")]) == 0
    augmented = tmp_path / "first" / "model_augmented.json"
    assert json.loads(augmented.read_text())["derived_inputs"]  # the speed's low-pass was added
    capsys.readouterr()
    args = ["diagnose", str(augmented), "--data", str(path), "--select", "joint", "--out", str(tmp_path / "again")]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "already has derived inputs" in err[0]
    assert not (tmp_path / "again").exists()
