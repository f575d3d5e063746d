"""An option of one export target (or of one kind of model file) given where nothing uses it is refused in one
line, not ignored: ``--real REAL --target c`` had written a double-precision C file without a word."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from support import write_model
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main

DATA = Path(__file__).resolve().parents[1] / "datasets"


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    folder = tmp_path_factory.mktemp("export_options")
    model, _ = synthetic_model()
    write_model(model, folder / "grouped.json")
    args = ["fit", "--model", "ar1", "--data", str(DATA / "rod_ar1.csv"), "--heat", "q_W_m2"]
    assert main([*args, "--out", str(folder / "ar1")]) == 0
    screw = ["screw", "identify", str(DATA / "screw_H.csv"), "--out", str(folder / "screw")]
    assert main(screw) == 0
    return {
        "grouped": folder / "grouped.json",
        "ar1": folder / "ar1" / "model.json",
        "screw": folder / "screw" / "screw_model.json",
    }


REFUSED = [
    ("grouped", ["--target", "c", "--real", "REAL"], "--real: an option of --target st or table"),
    ("grouped", ["--target", "json", "--name", "FB_X"], "--name: an option of --target st or table"),
    ("grouped", ["--target", "st", "--resolution-um", "1"], "--resolution-um: an option of --target sheet"),
    ("grouped", ["--target", "all", "--state", "T1=20,T2=20"], "--state: an option of --target cec"),
    ("grouped", ["--target", "all", "--tolerance-um", "1"], "--tolerance-um: an option of --target table or cec"),
    ("ar1", ["--target", "all", "--counts-limit", "100"], "--counts-limit: no target of this kind of model file"),
    ("ar1", ["--target", "c", "--name", "FB_A"], "--name: an option of --target st"),
    ("screw", ["--target", "c", "--source", "screw_H", "--name", "FB_S"], "--name: no target of this kind"),
]


@pytest.mark.parametrize("kind, args, message", REFUSED)
def test_an_option_no_target_written_takes_is_refused(models, tmp_path, capsys, kind, args, message):
    assert main(["export", str(models[kind]), *args, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "x").exists()


def test_the_options_a_target_takes_still_reach_it(models, tmp_path, capsys):
    """--target all with the ST name and the sheet's register: both written as asked; the AR(1) block keeps its
    own default name when none is given."""
    args = ["--target", "all", "--name", "FB_Spindle", "--resolution-um", "0.5", "--counts-limit", "2000"]
    assert main(["export", str(models["grouped"]), *args, "--out", str(tmp_path / "g")]) == 0, capsys.readouterr().err
    assert (tmp_path / "g" / "FB_Spindle.st").exists()
    sheet = json.loads((tmp_path / "g" / "groupfit_sheet.json").read_text())
    assert "0.5" in json.dumps(sheet) and "2000" in json.dumps(sheet)
    assert main(["export", str(models["ar1"]), "--target", "st", "--out", str(tmp_path / "a")]) == 0
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["FB_GroupfitAR1.st"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--source", "screw_H"], "--source screw_H: a ball-screw model's heat source; this model file has none"),
        (["--counts-limit", "7"], "--counts-limit: the size of an integer register"),
    ],
)
def test_replay_refuses_what_a_grouped_model_does_not_take(models, tmp_path, capsys, args, message):
    assert main(["replay", str(models["grouped"]), "--data", str(SYNTHETIC), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
