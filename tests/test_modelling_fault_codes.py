"""A modelling run's fault codes (-999 °C) outside the inputs: in the reference column the inputs are taken
against, and in a temperature the AR(1) model reads beside its heat column. A validation run keeps the inputs'
fault codes for the run-time rule (tests/test_validation_fault_codes.py); these it must not."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
MODELLING = DATASETS / "paper_cycle.csv"
QUICK = ["--p", "0", "--ridge", "0", "--recalibrate", "none", "--quiet"]


def cli(*args) -> int:
    try:
        return main([str(a) for a in args])
    except SystemExit as exc:
        return int(exc.code)


def with_code(tmp_path: Path, source: Path, column: str, rows: slice, name: str) -> Path:
    frame = pd.read_csv(source)
    frame[column] = frame[column].astype(float)
    frame.loc[rows, column] = -999.0
    frame.to_csv(tmp_path / name, index=False)
    return tmp_path / name


def coefficients(tmp_path: Path, path: Path) -> list:
    report = tmp_path / f"{path.stem}.json"
    assert cli("fit", "--data", path, *QUICK, "--json", report, "--out", tmp_path / path.stem) == 0
    return json.loads(report.read_text())["coefficients"]


def test_one_fault_code_in_the_reference_is_a_glitch_interpolated_as_in_an_input(tmp_path, capsys):
    once = with_code(tmp_path, MODELLING, "T_amb", slice(200, 200), "once.csv")
    mended = pd.read_csv(MODELLING)
    mended["T_amb"] = mended["T_amb"].astype(float)
    mended.loc[200, "T_amb"] = (mended.loc[199, "T_amb"] + mended.loc[201, "T_amb"]) / 2.0  # equally spaced rows
    mended.to_csv(tmp_path / "mended.csv", index=False)
    glitched, interpolated = coefficients(tmp_path, once), coefficients(tmp_path, tmp_path / "mended.csv")
    assert np.allclose(glitched, interpolated, rtol=1e-9, atol=1e-12)
    assert "'T_amb' row 201: -999 °C" in capsys.readouterr().out


def test_a_fault_code_in_the_reference_on_several_rows_is_refused_naming_its_row(tmp_path, capsys):
    coded = with_code(tmp_path, MODELLING, "T_amb", slice(200, 209), "coded.csv")
    assert cli("fit", "--data", coded, *QUICK, "--out", tmp_path / "m") == 2
    message = capsys.readouterr().err
    assert "row 201, column 'T_amb' = -999 °C (10 row(s)" in message and "--reference none" in message
    assert not (tmp_path / "m").exists()


@pytest.mark.parametrize(
    ("setting", "row"), [('structural_sensor = "T1"\nstructural_gain_um_per_K = 0.5', 200), ('ar1_scaling = "rise"', 0)]
)
def test_a_fault_code_the_ar1_model_reads_beside_its_heat_is_refused_in_a_validation_run(
    tmp_path, capsys, setting, row
):
    config = tmp_path / "compare.toml"
    config.write_text(f"[compare]\n{setting}\n", encoding="utf-8")
    coded = with_code(tmp_path, DATASETS / "validation_speed.csv", "T1", slice(row, row + 4), "coded.csv")
    args = ["compare", config, "--data", MODELLING, "--validate", coded, "--pmax", "0", "--quiet"]
    assert cli(*args, "--out", tmp_path / "c") == 2
    assert f"row {row + 1}, column 'T1' = -999 °C" in capsys.readouterr().err
