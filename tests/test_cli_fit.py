import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.fast_response import without_stage
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets" / "synthetic_cycle.csv"
SPEC_KEYS = {
    "format",
    "sampling_period_s",
    "temps",
    "error",
    "intercept",
    "objective",
    "p",
    "n",
    "c",
    "breaks",
    "soft_groups",
    "coefficients",
    "objective_value",
    "switching",
    "training",
}


def fit(tmp_path, *extra):
    out = tmp_path / "out"
    args = ["fit", "--data", str(DATA), "--temps", "T1,T2,T3,T4", "--out", str(out), "--quiet", *extra]
    return main(args), out


def test_fit_writes_model_figure_and_json(tmp_path, capsys):
    status, out = fit(tmp_path, "--p", "2", "--search", "exact", "--json", str(tmp_path / "fit.json"))
    report = capsys.readouterr().out
    assert status == 0
    assert (out / "fit.png").stat().st_size > 10_000
    result = json.loads((tmp_path / "fit.json").read_text())
    assert SPEC_KEYS <= set(result) and result["search"]["method"] == "exact" and result["search"]["seed"] is None
    model = without_stage(ModelFile.load(out / "model.json")).to_dict()  # the fitted groups, as training records them
    assert model["format"] == "groupfit-model/1" and model["p"] == 2 and len(model["coefficients"]) == 3
    assert model["breaks"] == result["breaks"]
    assert "Rg = " in report and str(model["breaks"]) in report

    run = load_run(DATA, temps=model["temps"])
    residual = run.error - GroupedRegressor.from_model_file(model).predict(run.temps)
    assert np.sqrt(np.mean(residual**2)) == pytest.approx(model["training"]["rms_um"], rel=1e-9)
    assert np.sum(np.abs(residual)) == pytest.approx(model["objective_value"], rel=1e-9)


def test_ga_fit_reports_its_distance_to_the_exact_optimum(tmp_path, capsys):
    status, _ = fit(tmp_path, "--p", "3", "--seed", "4", "--json", "-")
    captured = capsys.readouterr()
    assert status == 0
    result = json.loads(captured.out)  # stdout holds only the JSON
    assert result["search"]["method"] == "ga" and result["search"]["seed"] == 4
    assert result["search"]["gap_percent"] >= 0
    assert "GA gap" in captured.err


def test_same_seed_gives_the_same_model_file(tmp_path):
    first, out1 = fit(tmp_path / "a", "--p", "3", "--seed", "11")
    second, out2 = fit(tmp_path / "b", "--p", "3", "--seed", "11")
    assert first == second == 0
    assert (out1 / "model.json").read_bytes() == (out2 / "model.json").read_bytes()


def test_config_file_and_command_line_override(tmp_path):
    config = tmp_path / "run.toml"
    config.write_text(
        f'[data]\npath = "{DATA.as_posix()}"\ntemps = ["T1", "T3"]\n'
        '[model]\np = 2\nobjective = "sse"\nintercept = false\n[search]\nmethod = "exact"\n'
        f'[output]\ndir = "{(tmp_path / "cfg-out").as_posix()}"\n'
    )
    assert main(["fit", str(config), "--p", "1", "--quiet"]) == 0
    model = ModelFile.load(tmp_path / "cfg-out" / "model.json").to_dict()
    assert model["p"] == 1 and model["temps"] == ["T1", "T3"]
    assert model["objective"] == "sse" and model["intercept"] is False


def test_bad_config_key_is_one_line(tmp_path, capsys):
    config = tmp_path / "bad.toml"
    config.write_text("[model]\npee = 2\n")
    assert main(["fit", str(config), "--data", str(DATA), "--quiet", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown key 'pee' in [model]" in err[0] and "bad.toml" in err[0]


@pytest.mark.cli
def test_module_entry_point_and_usage_errors(capsys):
    with pytest.raises(SystemExit) as finished:
        main(["fit", "--help"])
    assert finished.value.code == 0 and "--search" in capsys.readouterr().out
    bad = subprocess.run([sys.executable, "-m", "groupfit", "fit", "--p", "x"], capture_output=True, text=True)
    assert bad.returncode == 2
    assert len(bad.stderr.strip().splitlines()) == 1 and "invalid p: 'x'" in bad.stderr


def test_unknown_criterion_is_rejected(tmp_path, capsys):
    status, out = fit(tmp_path, "--p", "1", "--search", "exact", "--criterion", "T9")
    assert status == 2
    assert "switching criterion 'T9'" in capsys.readouterr().err
    assert not (out / "model.json").exists() and not out.exists()
