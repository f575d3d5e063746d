"""``fit`` reports the model's error on held-out conditions, and warns when it is far above the in-sample one."""

import json

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict
from support.diagnose_scenarios import SPINDLE_SENSORS as SENSORS
from support.diagnose_scenarios import spindle_run

from groupfit.cli import main
from groupfit.grouping import serving_group_index
from groupfit.heldout.folds import make_folds


def fit_json(tmp_path, capsys, frame, temps, *extra):
    """``groupfit fit --p 0`` on ``frame``: its ``--json`` result and the report it printed."""
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    args = ["fit", "--data", str(path), "--temps", ",".join(temps), "--p", "0", "--reference", "none"]
    capsys.readouterr()
    assert main([*args, *extra, "--out", str(tmp_path / "m"), "--json", str(tmp_path / "fit.json")]) == 0
    return json.loads((tmp_path / "fit.json").read_text()), capsys.readouterr().out


def test_the_held_out_error_is_the_leave_one_condition_out_error(tmp_path, capsys):
    frame = spindle_run(21, hours=12.0)
    result, _ = fit_json(tmp_path, capsys, frame, SENSORS[:3])
    labels = make_folds([frame], ["speed_rpm"]).labels
    X, y = frame[SENSORS[:3]].to_numpy(), frame["error_um"].to_numpy()
    predicted = cross_val_predict(LinearRegression(), X, y, groups=labels, cv=LeaveOneGroupOut())
    check = result["held_out"]
    assert check["held_out_rms_um"] == pytest.approx(np.sqrt(np.mean((y - predicted) ** 2)), rel=1e-9)
    assert check["in_sample_rms_um"] == pytest.approx(result["training"]["rms_um"], rel=1e-9)
    assert check["folds"].startswith("leave-one-condition-out")


def test_a_model_on_sensors_that_only_drift_is_called_over_fitted(tmp_path, capsys):
    """Forty sensors that drift on their own absorb, in sample, a drift of the error they do not cause."""
    rng = np.random.default_rng(22)
    frame = spindle_run(22, hours=6.0)
    drifting = [f"T{k}" for k in range(9, 49)]
    for name in drifting:
        frame[name] = 20.0 + np.cumsum(rng.normal(scale=0.02, size=len(frame)))
    unsensed = np.cumsum(rng.normal(scale=0.05, size=len(frame)))
    frame["error_um"] = 3.0 * (frame["T1"] - 20.0) + unsensed + rng.normal(scale=0.02, size=len(frame))
    over, over_report = fit_json(tmp_path, capsys, frame, ["T1", *drifting])
    assert over["held_out"]["overfitted"] is True
    assert over["held_out"]["held_out_rms_um"] > 3 * over["held_out"]["in_sample_rms_um"]
    clean, clean_report = fit_json(tmp_path, capsys, frame, ["T1"])
    assert clean["held_out"]["overfitted"] is False
    # the one-sensor model is worse in sample and better on held-out conditions
    assert clean["training"]["rms_um"] > over["training"]["rms_um"]
    assert clean["held_out"]["held_out_rms_um"] < over["held_out"]["held_out_rms_um"]
    # the report says it in words, once, and only for the over-fitted model
    assert over_report.count("note    the model over-fits") == 1
    assert "over-fits" not in clean_report


def test_a_grouped_model_is_held_out_group_by_group(tmp_path, capsys):
    """Each group refitted without the held-out condition predicts its part of it, where it keeps > c·M samples."""
    frame = spindle_run(23, hours=6.0)
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    args = ["fit", "--data", str(path), "--temps", "T1,T2", "--p", "1", "--n", "2", "--c", "2", "--reference", "none"]
    capsys.readouterr()
    assert main([*args, "--quiet", "--out", str(tmp_path / "m"), "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    labels = make_folds([frame], ["speed_rpm"]).labels
    groups = serving_group_index(result["breaks"], len(frame), 2)
    X, y = frame[["T1", "T2"]].to_numpy(), frame["error_um"].to_numpy()
    squared, scored = 0.0, 0
    for label in np.unique(labels):
        for group in np.unique(groups[labels == label]):
            train, test = (groups == group) & (labels != label), (groups == group) & (labels == label)
            if train.sum() <= 2 * 3:  # c·M: the group could not be fitted without this condition
                continue
            fitted = LinearRegression().fit(X[train], y[train])
            squared += float(np.sum((y[test] - fitted.predict(X[test])) ** 2))
            scored += int(test.sum())
    check = result["held_out"]
    assert check["held_out_rms_um"] == pytest.approx(np.sqrt(squared / scored), rel=1e-8)
    # in sample: each group fitted on the samples it serves (the soft groups' overlap of n samples aside)
    served = [groups == g for g in (0, 1)]
    residual = np.concatenate([y[s] - LinearRegression().fit(X[s], y[s]).predict(X[s]) for s in served])
    assert check["in_sample_rms_um"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-8)
    assert check["in_sample_rms_um"] == pytest.approx(result["training"]["rms_um"], rel=1e-3)
    assert check["grouped"] is True and not check["overfitted"]


def test_held_out_check_needs_two_folds():
    from groupfit.heldout.check import held_out_check

    frame = pd.DataFrame({"time_s": np.arange(40) * 10.0, "T1": np.linspace(20, 21, 40)})
    frame["error_um"] = 2.0 * frame["T1"]
    X, y = frame[["T1"]].to_numpy(), frame["error_um"].to_numpy()
    assert held_out_check(X, y, [frame], {"time_s", "error_um", "T1"}) is not None  # blocks of time
    assert held_out_check(X[:1], y[:1], [frame.iloc[:1]], {"time_s", "error_um", "T1"}) is None
