"""A sweep killed half way and started again completes only the missing runs."""

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.sweep.config import read_study
from groupfit.sweep.store import StudyStore

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets" / "synthetic_cycle.csv"
MANY_SHORT_RUNS = """
[data]
path = "{data}"
[grid]
p = {{start = 0, stop = 5}}
n = {{start = 0, stop = 3}}
c = [2.0, 3.0]
objective = "sse"
search = "exact"
"""


def done_rows(db: Path) -> int:
    """Runs done in the database, read from another process while the sweep writes."""
    if not db.exists():
        return 0
    try:
        with sqlite3.connect(db, timeout=5) as connection:
            return connection.execute("SELECT COUNT(*) FROM runs WHERE status = 'done'").fetchone()[0]
    except sqlite3.OperationalError:  # the table is not created yet
        return 0


def process_group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def rows_by_hash(db):
    with StudyStore(db) as store:
        return {row["run_hash"]: row for row in store.rows()}


@pytest.mark.slow
@pytest.mark.cli
def test_killed_sweep_resumes_with_nothing_lost_and_nothing_duplicated(tmp_path):
    config = tmp_path / "many.toml"
    config.write_text(MANY_SHORT_RUNS.format(data=DATA.as_posix()), encoding="utf-8")
    study = read_study(config)
    total = len(study.runs)
    assert total == 6 * 4 * 2
    db = tmp_path / "killed.sqlite"

    command = [sys.executable, "-m", "groupfit", "sweep", str(config), "--db", str(db), "--workers", "1", "--quiet"]
    sweep = subprocess.Popen(command, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 60
        while done_rows(db) < 5:
            assert sweep.poll() is None, sweep.stderr.read().decode()
            assert time.monotonic() < deadline, "the sweep wrote no rows in 60 s"
            time.sleep(0.01)
        sweep.send_signal(signal.SIGKILL)  # the study process only, as kill -9 would
        sweep.wait(timeout=10)
        # its worker notices and exits by itself
        deadline = time.monotonic() + 10
        while process_group_alive(sweep.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not process_group_alive(sweep.pid), "a worker process outlived the killed sweep"
    finally:
        if process_group_alive(sweep.pid):
            os.killpg(sweep.pid, signal.SIGKILL)
        sweep.stderr.close()

    finished_before_kill = done_rows(db)
    assert 5 <= finished_before_kill < total, "the kill must land half way for this test to mean anything"

    report = tmp_path / "resume.json"
    assert main(["sweep", str(config), "--db", str(db), "--workers", "2", "--quiet", "--json", str(report)]) == 0
    resumed = json.loads(report.read_text())
    assert resumed["skipped"] == finished_before_kill
    assert resumed["done"] == total - finished_before_kill and resumed["failed"] == 0

    with sqlite3.connect(db) as connection:
        hashes = [row[0] for row in connection.execute("SELECT run_hash FROM runs WHERE status = 'done'")]
        assert connection.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == total
    assert sorted(hashes) == sorted(run.run_hash for run in study.runs)

    clean = tmp_path / "clean.sqlite"
    assert main(["sweep", str(config), "--db", str(clean), "--workers", "2", "--quiet"]) == 0
    resumed_rows, clean_rows = rows_by_hash(db), rows_by_hash(clean)
    assert set(resumed_rows) == set(clean_rows)
    for run_hash, row in clean_rows.items():
        assert resumed_rows[run_hash]["breaks"] == row["breaks"]
        assert resumed_rows[run_hash]["objective"] == pytest.approx(row["objective"], rel=1e-12)
        np.testing.assert_allclose(resumed_rows[run_hash]["coefficients"], row["coefficients"], rtol=1e-9)


@pytest.mark.slow
@pytest.mark.cli
def test_two_sweeps_on_one_database_share_the_runs(tmp_path):
    """Started together, two sweeps claim runs from the database: every run executes once."""
    config = tmp_path / "shared.toml"
    config.write_text(MANY_SHORT_RUNS.format(data=DATA.as_posix()), encoding="utf-8")
    total = len(read_study(config).runs)
    db = tmp_path / "shared.sqlite"
    reports = [tmp_path / f"sweep{k}.json" for k in range(2)]
    commands = [
        [sys.executable, "-m", "groupfit", "sweep", str(config), "--db", str(db), "--workers", "1", "--quiet"]
        + ["--json", str(report)]
        for report in reports
    ]
    sweeps = [subprocess.Popen(c, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) for c in commands]
    for sweep in sweeps:
        assert sweep.wait(timeout=300) == 0, sweep.stderr.read().decode()
        sweep.stderr.close()
    results = [json.loads(report.read_text()) for report in reports]
    executed = sum(r["done"] + r["failed"] for r in results)
    assert executed == total, results  # no run twice (before: up to 2 × total)
    for r in results:
        assert r["skipped"] + r["done"] + r["failed"] + r["elsewhere"] == total
    with sqlite3.connect(db) as connection:
        assert connection.execute("SELECT COUNT(*) FROM runs WHERE status = 'done'").fetchone()[0] == total
        assert connection.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0


def test_a_sweep_retries_the_journal_switch_another_sweep_holds(tmp_path, monkeypatch):
    """SQLite refuses the WAL switch at once when two sweeps open a new database together: it is tried again."""
    import groupfit.sweep.store as store

    refusals = []

    class Connection:
        def __init__(self, connection):
            self.connection = connection

        def execute(self, sql, *args):
            if sql.startswith("PRAGMA journal_mode") and len(refusals) < 3:
                refusals.append(sql)
                raise sqlite3.OperationalError("database is locked")
            return self.connection.execute(sql, *args)

        def __getattr__(self, name):
            return getattr(self.connection, name)

    real_connect = sqlite3.connect
    monkeypatch.setattr(store.sqlite3, "connect", lambda *a, **k: Connection(real_connect(*a, **k)))
    with StudyStore(tmp_path / "study.sqlite") as study:
        assert len(refusals) == 3
        assert study.connection.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    # a lock that outlasts the wait is still refused in one clear line
    monkeypatch.setattr(store, "BUSY_TIMEOUT_S", 0.0)
    refusals.clear()
    with pytest.raises(store.InputError, match="not a usable study database \\(database is locked\\)"):
        StudyStore(tmp_path / "other.sqlite")


def test_a_database_of_something_else_is_refused_and_left_as_it_was(tmp_path):
    app = tmp_path / "app.db"
    with sqlite3.connect(app) as connection:
        connection.execute("CREATE TABLE users (name TEXT)")
        connection.execute("INSERT INTO users VALUES ('ada')")
    connection.close()
    before = app.read_bytes()
    with pytest.raises(InputError, match=r"app.db: a database of something else \(tables users\)"):
        StudyStore(app)
    assert app.read_bytes() == before and not Path(f"{app}-wal").exists()
    # a study database opened again is its own
    with StudyStore(tmp_path / "study.sqlite"):
        pass
    with StudyStore(tmp_path / "study.sqlite") as study:
        assert study.connection.execute("PRAGMA user_version").fetchone()[0] > 0
