import json
import os
import sqlite3
from pathlib import Path

import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.sweep.config import read_study
from groupfit.sweep.runs import execute_run
from groupfit.sweep.store import StudyStore

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets" / "synthetic_cycle.csv"


def write_study(tmp_path, grid, ga="", name="study.toml"):
    config = tmp_path / name
    config.write_text(f'[data]\npath = "{DATA.as_posix()}"\n[grid]\n{grid}\n[ga]\n{ga}\n', encoding="utf-8")
    return config


def sweep(config, db, *extra):
    return main(["sweep", str(config), "--db", str(db), "--quiet", *extra])


def test_sweep_records_one_row_per_run_and_a_second_sweep_skips_them(tmp_path, capsys):
    config = write_study(
        tmp_path,
        'p = {start = 0, stop = 3}\nsearch = ["exact", "ga"]\nobjective = ["sae", "sse"]',
        "seed = [0, 1]\nmax_generations = [10]",
    )
    db = tmp_path / "study.sqlite"
    assert sweep(config, db, "--workers", "2", "--json", str(tmp_path / "first.json")) == 0
    first = json.loads((tmp_path / "first.json").read_text())
    study = read_study(config)
    total = len(study.runs)
    assert total == 2 * (1 + 3 * 3)
    assert first["db"] == str(db) and (first["done"], first["skipped"], first["failed"]) == (total, 0, 0)

    with sqlite3.connect(db) as connection:
        rows = connection.execute("SELECT run_hash, status, p, search, breaks, objective FROM runs").fetchall()
    assert len(rows) == total and {r[0] for r in rows} == {r.run_hash for r in study.runs}
    assert all(r[1] == "done" for r in rows)

    # every stored result is what the run gives when executed directly
    with StudyStore(db) as store:
        stored = {row["run_hash"]: row for row in store.rows()}
    for run in study.runs[::5]:
        direct = execute_run(run.spec, run.path)
        assert stored[run.run_hash]["breaks"] == direct["breaks"]
        assert stored[run.run_hash]["objective"] == pytest.approx(direct["objective"], rel=1e-12)
        assert stored[run.run_hash]["config"] == run.spec

    capsys.readouterr()
    assert sweep(config, db, "--workers", "2", "--json", "-") == 0
    second = json.loads(capsys.readouterr().out)
    assert (second["done"], second["skipped"], second["failed"]) == (0, total, 0)


def test_failed_runs_are_recorded_not_fatal_and_tried_again(tmp_path, capsys):
    config = write_study(tmp_path, "p = [1, 40]")
    db = tmp_path / "s.sqlite"
    assert sweep(config, db, "--workers", "1", "--json", str(tmp_path / "r.json")) == 0
    result = json.loads((tmp_path / "r.json").read_text())
    assert (result["done"], result["skipped"], result["failed"]) == (1, 0, 1)
    assert "p = 40 breaks do not fit" in result["failures"][0]["error"]
    assert "p = 40 breaks do not fit" in capsys.readouterr().out
    with sqlite3.connect(db) as connection:
        status = dict(connection.execute("SELECT p, status FROM runs").fetchall())
        message = connection.execute("SELECT error FROM runs WHERE p = 40").fetchone()[0]
    assert status == {1: "done", 40: "failed"} and "largest feasible p" in message
    assert (
        sweep(config, db, "--workers", "1", "--json", str(tmp_path / "r.json"), "--report", str(tmp_path / "rep")) == 0
    )
    again = json.loads((tmp_path / "r.json").read_text())
    failed_section = (tmp_path / "rep" / "summary.md").read_text().split("## Failed runs")[1]
    assert "| 40 |" in failed_section and "do not fit" in failed_section
    assert (again["done"], again["skipped"], again["failed"]) == (0, 1, 1)
    with sqlite3.connect(db) as connection:
        assert connection.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 2


def test_report_writes_tables_and_figures(tmp_path):
    config = write_study(
        tmp_path, 'p = [0, 1, 2]\nsearch = ["exact", "ga"]\nn = [1, 3]', "seed = [0, 1]\nmax_generations = [5, 20]"
    )
    report = tmp_path / "report"
    assert sweep(config, tmp_path / "s.sqlite", "--workers", "2", "--report", str(report)) == 0
    for name in (
        "runs.csv",
        "summary.csv",
        "summary.md",
        "objective_vs_p.png",
        "break_stability.png",
        "ga_success.png",
    ):
        assert (report / name).stat().st_size > 200, name
    text = (report / "summary.md").read_text()
    assert "## Objective against p" in text and "## GA success against budget" in text
    import pandas as pd

    summary = pd.read_csv(report / "summary.csv")
    assert len(summary) == 2 * 3  # (n) × (p)
    assert (summary["best_objective"] >= summary["exact_objective"] * (1 - 1e-9)).all()
    success_rows = [
        line.split("|")[1:-1]
        for line in text.split("## GA success against budget")[1].splitlines()
        if line.startswith("| yes | 60 ")
    ]
    assert sorted({int(cells[3]) for cells in success_rows}) == [300, 1200]  # population 60 × 5 and × 20
    assert {int(cells[4]) for cells in success_rows} == {1, 2}  # p = 0 has no GA runs


def test_default_database_is_named_after_the_study(tmp_path, monkeypatch):
    config = write_study(tmp_path, "p = [1]", name="tiny.toml")
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", str(config), "--workers", "1", "--quiet"]) == 0
    assert (tmp_path / "tiny.sqlite").is_file()


def test_bad_study_is_one_line_exit_2(tmp_path, capsys):
    config = tmp_path / "bad.toml"
    config.write_text(f'[data]\npath = "{DATA.as_posix()}"\n[grid]\npp = [1]\n')
    assert main(["sweep", str(config), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown key 'pp' in [grid]" in err[0] and "bad.toml" in err[0]


def test_unreachable_scheduler_is_one_line_exit_2(tmp_path, capsys):
    pytest.importorskip("dask.distributed")
    config = write_study(tmp_path, "p = [1]")
    status = main(
        [
            "sweep",
            str(config),
            "--db",
            str(tmp_path / "s.sqlite"),
            "--quiet",
            "--scheduler",
            "tcp://127.0.0.1:9",
            "--connect-timeout",
            "1",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2
    assert len(err) == 1 and "cannot reach the Dask scheduler" in err[0] and "tcp://127.0.0.1:9" in err[0]
    assert not (tmp_path / "s.sqlite").exists()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--scheduler", ""], "--scheduler '': an empty address"),
        (["--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "-1"], "--connect-timeout -1: give the seconds"),
        (["--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "nan"], "--connect-timeout nan: give the seconds"),
    ],
)
def test_an_empty_scheduler_or_a_bad_wait_is_refused_before_any_run(tmp_path, capsys, args, message):
    """An empty address ran the study locally; a negative wait reached Dask as the string '1-1.0'."""
    config = write_study(tmp_path, "p = [1]")
    assert main(["sweep", str(config), "--db", str(tmp_path / "s.sqlite"), "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not (tmp_path / "s.sqlite").exists()


def test_more_workers_than_cores_is_said(tmp_path, capsys):
    config = write_study(tmp_path, "p = [1]")
    workers = (os.cpu_count() or 1) + 1
    assert main(["sweep", str(config), "--db", str(tmp_path / "s.sqlite"), "--workers", str(workers)]) == 0
    assert f"note    --workers {workers} on {workers - 1} core(s)" in capsys.readouterr().out


def test_store_replaces_a_failed_row_when_the_run_is_done(tmp_path):
    config = write_study(tmp_path, "p = [1]")
    run = read_study(config).runs[0]
    with StudyStore(tmp_path / "s.sqlite") as store:
        store.record(run, {"status": "failed", "error": "boom", "timings": {}}, "s")
        assert store.done_hashes() == set()
        store.record(run, execute_run(run.spec, run.path), "s")
        assert store.done_hashes() == {run.run_hash}
        rows = store.rows()
    assert len(rows) == 1 and rows[0]["status"] == "done" and rows[0]["error"] is None
    assert rows[0]["breaks"] == [94]
    with sqlite3.connect(tmp_path / "s.sqlite") as connection:
        assert connection.execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def test_a_report_replaces_its_own_tables_but_not_a_users_table_of_that_name(tmp_path, capsys):
    config = write_study(tmp_path, "p = [0, 1]")
    report = tmp_path / "report"
    assert sweep(config, tmp_path / "s.sqlite", "--workers", "1", "--report", str(report)) == 0
    first = (report / "runs.csv").read_bytes()
    assert sweep(config, tmp_path / "s.sqlite", "--workers", "1", "--report", str(report)) == 0
    assert (report / "runs.csv").read_bytes().splitlines()[0] == first.splitlines()[0]

    users = b"time_s,T1,error_um\n0,20.1,0.5\n"  # a log of the user's that happens to be called runs.csv
    (report / "runs.csv").write_bytes(users)
    before = {p.name: p.read_bytes() for p in report.iterdir()}
    capsys.readouterr()
    assert sweep(config, tmp_path / "s.sqlite", "--workers", "1", "--report", str(report)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "runs.csv: --out would replace a table that is not an earlier output" in err[0]
    assert {p.name: p.read_bytes() for p in report.iterdir()} == before
    assert sweep(config, tmp_path / "s.sqlite", "--workers", "1", "--report", str(report), "--force") == 0
    assert (report / "runs.csv").read_bytes().splitlines()[0] == first.splitlines()[0]


def test_a_hot_sensor_is_taken_with_the_range_the_refusal_advises(tmp_path, capsys):
    frame = pd.read_csv(DATA)
    frame["T1"] = frame["T1"] + 500.0  # a furnace wall: above the default plausible 500 °C
    hot = tmp_path / "hot.csv"
    frame.to_csv(hot, index=False)
    config = tmp_path / "hot.toml"
    grid = '[grid]\np = [0]\nsearch = ["exact"]\n'
    config.write_text(f'[data]\npath = "{hot.as_posix()}"\n{grid}', encoding="utf-8")
    assert sweep(config, tmp_path / "a.sqlite") == 2
    err = capsys.readouterr().err
    assert "--range-temp=LOW,HIGH (or [data] temp_range)" in err and not (tmp_path / "a.sqlite").exists()
    assert sweep(config, tmp_path / "b.sqlite", "--range-temp=-50,1000", "--out", str(tmp_path / "b")) == 0
    wide = tmp_path / "wide.toml"
    wide.write_text(f'[data]\npath = "{hot.as_posix()}"\ntemp_range = [-50, 1000]\n{grid}', encoding="utf-8")
    assert sweep(wide, tmp_path / "c.sqlite", "--out", str(tmp_path / "c")) == 0
    wide.write_text(f'[data]\npath = "{hot.as_posix()}"\ntemp_range = [1000, -50]\n{grid}', encoding="utf-8")
    assert sweep(wide, tmp_path / "d.sqlite") == 2
    assert "temp_range" in capsys.readouterr().err
