"""A sweep whose grouped runs would hold more table memory at once than the budget is refused before any run."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.commands import common
from groupfit.errors import InputError
from groupfit.objective import segment_table_bytes
from groupfit.sweep.config import read_study
from groupfit.sweep.feasibility import check_table_memory

DATA = Path(__file__).resolve().parents[1] / "datasets" / "synthetic_cycle.csv"


def study_file(tmp_path, p: str) -> Path:
    config = tmp_path / "study.toml"
    config.write_text(f'[data]\npath = "{DATA.as_posix()}"\n[grid]\np = {p}\nsearch = ["exact"]\n', encoding="utf-8")
    return config


def one_table() -> float:
    frame = pd.read_csv(DATA)
    inputs = [c for c in frame.columns if c.startswith("T")]
    return segment_table_bytes(len(frame), len(inputs) + 1)


def test_the_largest_tables_held_together_are_counted_per_worker(tmp_path):
    study = read_study(study_file(tmp_path, "[0, 1, 2]"))
    table = one_table()
    assert check_table_memory(study, study.runs, "s", budget_bytes=1.5 * table, workers=1) == pytest.approx(table)
    with pytest.raises(InputError, match=r"2 at once on 2 worker\(s\).*N = \d+, M = \d+ coefficients"):
        check_table_memory(study, study.runs, "s", budget_bytes=1.5 * table, workers=2)
    # two grouped runs only: a third worker holds nothing more
    assert check_table_memory(study, study.runs, "s", budget_bytes=2 * table, workers=3) == pytest.approx(2 * table)
    global_only = read_study(study_file(tmp_path, "[0]"))
    assert check_table_memory(global_only, global_only.runs, "s", budget_bytes=0.0, workers=2) == 0.0


def test_the_sweep_refuses_in_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    config = study_file(tmp_path, "[0, 1]")
    monkeypatch.setattr(common, "EXACT_BUDGET_BYTES", 0.5 * one_table())
    db = tmp_path / "study.sqlite"
    assert main(["sweep", str(config), "--db", str(db), "--workers", "1", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "tables of segment sums" in err and "--no-budget" in err
    assert not db.exists() and not (tmp_path / "groupfit-out").exists()
