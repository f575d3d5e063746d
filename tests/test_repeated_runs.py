"""A run given twice (the same path, a link to it, or a copy of its bytes) is refused in one line by every verb
that reads several runs: held out against itself, a run scores nothing. So are the options about the runs that
would be ignored: --continues without a run to continue, --keep-reference without a reference."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from groupfit.cli import main

DATA = Path(__file__).resolve().parents[1] / "datasets"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("repeated")
    shutil.copy(DATA / "diag_none_model.csv", folder / "a.csv")
    shutil.copy(DATA / "diag_none_validate.csv", folder / "b.csv")
    shutil.copy(folder / "a.csv", folder / "copy.csv")
    os.symlink(folder / "a.csv", folder / "link.csv")
    assert main(["fit", "--data", str(folder / "a.csv"), "--p", "0", "--quiet", "--out", str(folder / "m")]) == 0
    return folder


CASES = {
    "fit, the same path": (["fit", "--data", "a.csv", "a.csv", "--p", "0"], "a.csv: given twice as data"),
    "fit, a copy": (["fit", "--data", "a.csv", "copy.csv", "--p", "0"], "copy.csv: holds the same bytes as"),
    "compare, a link": (["compare", "--data", "a.csv", "--validate", "link.csv"], "link.csv: given twice as data"),
    "compare, a copy": (["compare", "--data", "a.csv", "--validate", "b.csv", "copy.csv"], "copy.csv: holds the same"),
    "diagnose, a copy": (["diagnose", "m/model.json", "--data", "a.csv", "--validate", "copy.csv"], "copy.csv: holds"),
    "replay, continues": (["replay", "m/model.json", "--data", "copy.csv", "--continues", "a.csv"], "copy.csv: holds"),
}


@pytest.mark.parametrize("label", list(CASES))
def test_a_run_given_twice_is_refused_and_nothing_written(runs, tmp_path, capsys, label):
    argv, message = CASES[label]
    argv = [str(runs / a) if a.endswith((".csv", ".json")) else a for a in argv]
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path / "o"), "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "o").exists() and not (tmp_path / "r.json").exists()


def test_two_different_runs_are_read(runs, tmp_path, capsys):
    argv = ["compare", "--data", str(runs / "a.csv"), "--validate", str(runs / "b.csv"), "--pmax", "0", "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "o")]) == 0, capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [
        ["compare", "--data", "a.csv", "--continues", "--pmax", "0"],
        ["diagnose", "m/model.json", "--data", "a.csv", "--continues"],
    ],
    ids=["compare", "diagnose"],
)
def test_continues_without_a_validation_run_is_refused_not_ignored(runs, tmp_path, capsys, argv):
    argv = [str(runs / a) if a.endswith((".csv", ".json")) else a for a in argv]
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--continues: says each --validate" in err[0] and "give --validate RUN" in err[0]
    assert not (tmp_path / "o").exists()


def test_keep_reference_on_a_model_without_one_is_refused(runs, tmp_path, capsys):
    argv = ["fit", "--data", str(runs / "a.csv"), "--p", "0", "--reference", "none", "--out", str(tmp_path / "m")]
    assert main([*argv, "--quiet"]) == 0
    capsys.readouterr()
    args = ["diagnose", str(tmp_path / "m" / "model.json"), "--data", str(runs / "a.csv"), "--keep-reference"]
    assert main([*args, "--out", str(tmp_path / "d")]) == 2
    assert "--keep-reference: " in capsys.readouterr().err and not (tmp_path / "d").exists()
