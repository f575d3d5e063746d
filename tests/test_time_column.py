"""A model remembers the time column it was fitted with: diagnose and replay read the next runs with it."""

import json
from pathlib import Path

import pandas as pd

from groupfit.cli import main

DATA = Path(__file__).resolve().parents[1] / "datasets"
TIME = "时间/s"  # the measured spindle test came with a Chinese time header


def renamed(tmp_path, name):
    path = tmp_path / f"{name}.csv"
    pd.read_csv(DATA / f"{name}.csv").rename(columns={"time_s": TIME}).to_csv(path, index=False)
    return path


def test_diagnose_and_replay_read_the_time_column_the_model_was_fitted_with(tmp_path, capsys):
    model_run, other = renamed(tmp_path, "diag_speed_model"), renamed(tmp_path, "diag_speed_validate")
    fit = ["fit", "--data", str(model_run), "--time", TIME, "--temps", "T1,T2", "--p", "0", "--quiet"]
    assert main([*fit, "--out", str(tmp_path / "m")]) == 0
    model = tmp_path / "m" / "model.json"
    assert json.loads(model.read_text())["training"]["time"] == TIME

    results = {}
    for label, extra in (("remembered", []), ("given", ["--time", TIME])):
        capsys.readouterr()
        diagnose = ["diagnose", str(model), "--data", str(model_run), "--validate", str(other), "--json", "-"]
        assert main([*diagnose, "--out", str(tmp_path / f"d_{label}"), *extra]) == 0
        found = json.loads(capsys.readouterr().out)
        assert main(["replay", str(model), "--data", str(other), "--json", "-", *extra]) == 0
        results[label] = found, json.loads(capsys.readouterr().out)["rms_um"]
    (remembered, rms), (given, rms_given) = results["remembered"], results["given"]
    assert remembered["added"] and remembered["added"] == given["added"]
    assert remembered["after"] == given["after"]
    assert rms == rms_given and rms > 0
    augmented = json.loads((tmp_path / "d_remembered" / "model_augmented.json").read_text())
    assert augmented["training"]["time"] == TIME


def test_a_model_file_without_its_time_column_reads_time_s_else_the_column_named_as_the_time(tmp_path, capsys):
    model_run = renamed(tmp_path, "diag_speed_model")
    fit = ["fit", "--data", str(model_run), "--time", TIME, "--temps", "T1,T2", "--p", "0", "--quiet"]
    assert main([*fit, "--out", str(tmp_path / "m")]) == 0
    model = tmp_path / "m" / "model.json"
    data = json.loads(model.read_text())
    del data["training"]["time"]
    model.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["diagnose", str(model), "--data", str(model_run), "--out", str(tmp_path / "d")]) == 0
    out = capsys.readouterr()
    assert f"time from column '{TIME}' (there is no 'time_s'" in out.out + out.err


def test_a_next_run_without_the_models_time_column_is_read_on_the_one_its_name_marks(tmp_path, capsys):
    german = tmp_path / "model_run.csv"
    pd.read_csv(DATA / "diag_speed_model.csv").rename(columns={"time_s": "Zeit [s]"}).to_csv(german, index=False)
    fit = ["fit", "--data", str(german), "--temps", "T1,T2", "--p", "0", "--quiet", "--out", str(tmp_path / "m")]
    assert main(fit) == 0
    model = tmp_path / "m" / "model.json"
    assert json.loads(model.read_text())["training"]["time"] == "Zeit [s]"
    other = DATA / "diag_speed_validate.csv"  # its clock is time_s
    same = tmp_path / "validate_zeit.csv"
    pd.read_csv(other).rename(columns={"time_s": "Zeit [s]"}).to_csv(same, index=False)
    capsys.readouterr()
    assert main(["replay", str(model), "--data", str(other), "--json", "-"]) == 0
    captured = capsys.readouterr()
    assert "time from column 'time_s' (there is no 'Zeit [s]'" in captured.err
    assert main(["replay", str(model), "--data", str(same), "--json", "-"]) == 0
    assert json.loads(captured.out)["rms_um"] == json.loads(capsys.readouterr().out)["rms_um"]
    assert main(["replay", str(model), "--data", str(other), "--time", "Zeit [s]"]) == 2  # asked for: refused
    assert "column 'Zeit [s]' not found" in capsys.readouterr().err
