"""The study database: one SQLite row per run, keyed by the hash of its specification.

Schema (table ``runs``; JSON columns hold JSON text)::

    run_hash        TEXT PRIMARY KEY   sha256 of the canonical JSON of the spec
    study           TEXT               [study] name of the study that ran it
    dataset         TEXT               data file name (stem)
    data_path       TEXT               data file path when it ran
    data_sha256     TEXT               hash of the data file's bytes
    status          TEXT               'done' or 'failed'
    error           TEXT               message of a failed run
    search          TEXT               'exact' or 'ga'
    objective_kind  TEXT               'sae' or 'sse'
    p, n            INTEGER
    c               REAL
    intercept       INTEGER            0 or 1
    seed, population_size, max_generations   INTEGER (GA runs; NULL otherwise)
    sensors_spec    JSON               {"names": [...]} or the selection
    sensors         JSON               the input columns used
    objective       REAL               Rg of the fitted model (µm or µm²)
    exact_objective REAL               exact optimum (exact runs; certified GA runs)
    gap_percent     REAL               100·(GA − exact)/exact
    breaks          JSON               hard breaks, 1-based
    exact_breaks    JSON
    coefficients    JSON               one list per soft group, intercept first
    result          JSON               everything execute_run returned
    config          JSON               the full run specification
    seconds         REAL               wall time of the run on its worker
    timings         JSON               seconds per stage
    worker          TEXT               host:pid
    finished_at     TEXT               UTC, ISO 8601
    groupfit_version TEXT

Concurrent sweeps on one database share the work through the table
``claims`` (``run_hash`` PRIMARY KEY, ``owner`` host:pid, ``expires`` Unix
time): a sweep claims a batch of runs that are neither done nor claimed by
another live sweep (:meth:`StudyStore.claim`, one ``BEGIN IMMEDIATE``
transaction), runs them, and drops each claim when it records the run. A
claim lapses when its lease expires or, on the same host, when its owner
process is gone, so a killed sweep never blocks its runs.

Only the processes that run the study write. A row is written when its run
has finished, in its own transaction (``INSERT OR REPLACE`` on the hash), in
WAL mode: a study killed at any moment keeps every finished run, loses at most
the runs in flight, and never holds a run twice. A run counts as done only
with ``status = 'done'``; failed runs are tried again by the next sweep.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import socket
import sqlite3
import time
from pathlib import Path
from typing import Iterable

from groupfit import __version__
from groupfit.errors import InputError
from groupfit.sweep.config import RunSpec

SCHEMA_VERSION = 1
BUSY_TIMEOUT_S = 30.0
"""How long a sweep waits for another one that holds the database."""
COLUMNS = (
    ("run_hash", "TEXT PRIMARY KEY"),
    ("study", "TEXT"),
    ("dataset", "TEXT"),
    ("data_path", "TEXT"),
    ("data_sha256", "TEXT"),
    ("status", "TEXT NOT NULL CHECK (status IN ('done', 'failed'))"),
    ("error", "TEXT"),
    ("search", "TEXT"),
    ("objective_kind", "TEXT"),
    ("p", "INTEGER"),
    ("n", "INTEGER"),
    ("c", "REAL"),
    ("intercept", "INTEGER"),
    ("seed", "INTEGER"),
    ("population_size", "INTEGER"),
    ("max_generations", "INTEGER"),
    ("sensors_spec", "TEXT"),
    ("sensors", "TEXT"),
    ("objective", "REAL"),
    ("exact_objective", "REAL"),
    ("gap_percent", "REAL"),
    ("breaks", "TEXT"),
    ("exact_breaks", "TEXT"),
    ("coefficients", "TEXT"),
    ("result", "TEXT"),
    ("config", "TEXT"),
    ("seconds", "REAL"),
    ("timings", "TEXT"),
    ("worker", "TEXT"),
    ("finished_at", "TEXT"),
    ("groupfit_version", "TEXT"),
)
JSON_COLUMNS = ("sensors_spec", "sensors", "breaks", "exact_breaks", "coefficients", "result", "config", "timings")


class StudyStore:
    """Read and write a study database.

    Parameters
    ----------
    path : path
        The SQLite file; created with its folder when missing.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if self.path.exists() and self.path.is_dir():
            raise InputError(f"{self.path}: the study database path is a folder; give a file with --db")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.connection = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT_S, isolation_level=None)
            self._check_foreign_tables()
            _switch_to_wal(self.connection)
            self.connection.execute("PRAGMA synchronous = NORMAL")
            self._create()
        except sqlite3.DatabaseError as exc:
            raise InputError(f"{self.path}: not a usable study database ({exc})") from None
        except OSError as exc:
            raise InputError(f"{self.path}: cannot create the study database ({exc.strerror})") from None

    def _check_foreign_tables(self) -> None:
        """Refuse a SQLite database that holds tables of something else (a study writes only its own)."""
        names = self.connection.execute(
            "SELECT name FROM sqlite_master WHERE type IN ('table', 'view') AND name NOT LIKE 'sqlite_%'"
        ).fetchall()
        foreign = sorted({name for (name,) in names} - {"runs", "claims"})
        if foreign:
            self.connection.close()
            raise InputError(
                f"{self.path}: a database of something else (tables {', '.join(foreign)}), not a study database; "
                "give another --db"
            )

    def _create(self) -> None:
        version = self.connection.execute("PRAGMA user_version").fetchone()[0]
        if version not in (0, SCHEMA_VERSION):
            raise InputError(f"{self.path}: study database schema {version}; this groupfit reads {SCHEMA_VERSION}")
        columns = ",\n    ".join(f"{name} {kind}" for name, kind in COLUMNS)
        with self.transaction():
            self.connection.execute(f"CREATE TABLE IF NOT EXISTS runs (\n    {columns}\n)")
            self.connection.execute("CREATE INDEX IF NOT EXISTS runs_by_study ON runs (study, status)")
            self.connection.execute(
                "CREATE TABLE IF NOT EXISTS claims (run_hash TEXT PRIMARY KEY, owner TEXT, expires REAL)"
            )
            self.connection.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")

    def transaction(self):
        return _Transaction(self.connection)

    def close(self) -> None:
        self.connection.close()

    def __enter__(self) -> "StudyStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def done_hashes(self, hashes: Iterable[str] | None = None) -> set[str]:
        """Hashes of the runs already done (among ``hashes`` when given)."""
        rows = self.connection.execute("SELECT run_hash FROM runs WHERE status = 'done'").fetchall()
        done = {row[0] for row in rows}
        return done if hashes is None else done.intersection(hashes)

    def claim(self, hashes: Iterable[str], owner: str, lease_s: float, limit: int) -> list[str]:
        """Claim up to ``limit`` of ``hashes`` (in order) that are not done and not claimed by another live sweep.

        Claims held by ``owner`` are renewed and returned first.
        """
        now = time.time()
        with self.transaction():
            done = {row[0] for row in self.connection.execute("SELECT run_hash FROM runs WHERE status = 'done'")}
            claims = {
                row[0]: (row[1], row[2])
                for row in self.connection.execute("SELECT run_hash, owner, expires FROM claims")
            }
            chosen = []
            for run_hash in hashes:
                if len(chosen) >= limit:
                    break
                if run_hash in done:
                    continue
                holder = claims.get(run_hash)
                if holder is not None and holder[0] != owner and holder[1] > now and _owner_alive(holder[0]):
                    continue
                chosen.append(run_hash)
            self.connection.executemany(
                "INSERT OR REPLACE INTO claims (run_hash, owner, expires) VALUES (?, ?, ?)",
                [(run_hash, owner, now + lease_s) for run_hash in chosen],
            )
        return chosen

    def claimed_elsewhere(self, hashes: Iterable[str], owner: str) -> set[str]:
        """Those of ``hashes`` that another live sweep holds a claim on."""
        now = time.time()
        rows = self.connection.execute("SELECT run_hash, owner, expires FROM claims").fetchall()
        held = {h for h, who, expires in rows if who != owner and expires > now and _owner_alive(who)}
        return held.intersection(hashes)

    def release(self, owner: str) -> None:
        """Drop every claim ``owner`` still holds (runs it did not get to)."""
        with self.transaction():
            self.connection.execute("DELETE FROM claims WHERE owner = ?", (owner,))

    def record(self, run: RunSpec, result: dict, study: str) -> None:
        """Write one finished run (done or failed) in its own transaction."""
        spec, search = run.spec, run.spec["search"]
        model = spec["model"]
        row = {
            "run_hash": run.run_hash,
            "study": study,
            "dataset": run.dataset,
            "data_path": run.path,
            "data_sha256": spec["data"]["sha256"],
            "status": result["status"],
            "error": result.get("error"),
            "search": search["method"],
            "objective_kind": model["objective"],
            "p": model["p"],
            "n": model["n"],
            "c": model["c"],
            "intercept": int(model["intercept"]),
            "seed": search.get("seed"),
            "population_size": search.get("population_size"),
            "max_generations": search.get("max_generations"),
            "sensors_spec": spec["sensors"],
            "sensors": result.get("sensors"),
            "objective": result.get("objective"),
            "exact_objective": result.get("exact_objective"),
            "gap_percent": result.get("gap_percent"),
            "breaks": result.get("breaks"),
            "exact_breaks": result.get("exact_breaks"),
            "coefficients": result.get("coefficients"),
            "result": result,
            "config": spec,
            "seconds": result.get("timings", {}).get("total"),
            "timings": result.get("timings"),
            "worker": result.get("worker"),
            "finished_at": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "groupfit_version": __version__,
        }
        for name in JSON_COLUMNS:
            if row[name] is not None:
                row[name] = json.dumps(row[name], sort_keys=True, allow_nan=True)
        names = [name for name, _ in COLUMNS]
        placeholders = ", ".join(f":{name}" for name in names)
        with self.transaction():
            self.connection.execute(f"INSERT OR REPLACE INTO runs ({', '.join(names)}) VALUES ({placeholders})", row)
            self.connection.execute("DELETE FROM claims WHERE run_hash = ?", (run.run_hash,))

    def rows(self, hashes: Iterable[str] | None = None) -> list[dict]:
        """Rows as dicts with JSON columns decoded (only ``hashes`` when given, in that order)."""
        cursor = self.connection.execute("SELECT * FROM runs ORDER BY rowid")
        names = [d[0] for d in cursor.description]
        rows = {}
        for values in cursor.fetchall():
            row = dict(zip(names, values))
            for name in JSON_COLUMNS:
                if row[name] is not None:
                    row[name] = json.loads(row[name])
            row["intercept"] = bool(row["intercept"]) if row["intercept"] is not None else None
            rows[row["run_hash"]] = row
        if hashes is None:
            return list(rows.values())
        return [rows[h] for h in hashes if h in rows]


def claim_owner() -> str:
    """This process as a claim owner: ``host:pid``."""
    return f"{socket.gethostname()}:{os.getpid()}"


def _owner_alive(owner: str) -> bool:
    """Whether a claim's owner may still be running (always true for another host: its lease decides)."""
    host, _, pid = owner.rpartition(":")
    if host != socket.gethostname() or not pid.isdigit():
        return True
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _switch_to_wal(connection: sqlite3.Connection) -> None:
    """``PRAGMA journal_mode = WAL``, retried while another sweep holds the database.

    Two sweeps opening a new database together can both read it and then both
    ask for the exclusive lock the switch needs; SQLite then answers one of
    them "database is locked" at once instead of waiting (its busy handler is
    not called where waiting could deadlock). The other finishes the switch
    within milliseconds, so the refused one tries again.
    """
    deadline = time.monotonic() + BUSY_TIMEOUT_S
    while True:
        try:
            connection.execute("PRAGMA journal_mode = WAL")
            return
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) or time.monotonic() >= deadline:
                raise
            time.sleep(0.05)


class _Transaction:
    """``BEGIN IMMEDIATE`` … ``COMMIT`` (or ``ROLLBACK`` on an exception)."""

    def __init__(self, connection: sqlite3.Connection):
        self.connection = connection

    def __enter__(self):
        self.connection.execute("BEGIN IMMEDIATE")
        return self.connection

    def __exit__(self, exc_type, exc, tb) -> None:
        self.connection.execute("ROLLBACK" if exc_type else "COMMIT")
