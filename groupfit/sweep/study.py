"""Run a study: skip the runs already done, execute the rest, record each as it finishes."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from groupfit.sweep.config import Study
from groupfit.sweep.store import StudyStore, claim_owner

CLAIM_LEASE_S = 6 * 3600.0
"""How long a claim holds without its owner recording a run (a crashed sweep on another host)."""
CLAIM_BATCH_PER_WORKER = 4
CLAIM_BATCH_MIN = 8
CLAIM_BATCHES = 4
"""A sweep claims runs in batches of at least this share of the study, so that concurrent sweeps share it."""


@dataclass
class StudyOutcome:
    """What one sweep did.

    Attributes
    ----------
    db : Path
    total : int
        Runs in the study.
    done : int
        Runs completed by this sweep.
    skipped : int
        Runs found done in the database and not run again.
    failed : int
        Runs that failed in this sweep (recorded with their message; tried
        again by the next sweep).
    seconds : float
    failures : list of (str, str)
        ``(run hash, message)`` of the failed runs.
    elsewhere : int
        Runs another sweep on the same database ran, or was running, meanwhile.
    """

    db: Path
    total: int
    done: int = 0
    skipped: int = 0
    failed: int = 0
    seconds: float = 0.0
    failures: list[tuple[str, str]] = field(default_factory=list)
    elsewhere: int = 0


def run_study(
    study: Study,
    store: StudyStore,
    executor,
    progress: Callable[[int], None] | None = None,
) -> StudyOutcome:
    """Execute every run of ``study`` that ``store`` does not hold as done.

    Parameters
    ----------
    study : Study
    store : StudyStore
    executor : LocalExecutor or DaskExecutor
        Anything with ``run(runs)`` yielding ``(run, result)`` as runs finish.
    progress : callable, optional
        Called with 1 after each finished run.
    """
    start = time.perf_counter()
    done_before = store.done_hashes(run.run_hash for run in study.runs)
    pending = [run for run in study.runs if run.run_hash not in done_before]
    outcome = StudyOutcome(db=store.path, total=len(study.runs), skipped=len(study.runs) - len(pending))
    by_hash = {run.run_hash: run for run in pending}
    owner = claim_owner()
    finished: set[str] = set()
    workers = int(getattr(executor, "workers", 0) or 4)
    batch = max(CLAIM_BATCH_MIN, CLAIM_BATCH_PER_WORKER * workers, -(-len(pending) // CLAIM_BATCHES))
    try:
        while True:
            claimed = store.claim([h for h in by_hash if h not in finished], owner, CLAIM_LEASE_S, batch)
            if not claimed:
                break
            for run, result in executor.run([by_hash[h] for h in claimed]):
                store.record(run, result, study.name)
                finished.add(run.run_hash)
                if result["status"] == "done":
                    outcome.done += 1
                else:
                    outcome.failed += 1
                    outcome.failures.append((run.run_hash, result.get("error") or "unknown error"))
                if progress is not None:
                    progress(1)
            finished.update(claimed)  # a run the executor did not return is not claimed again by this sweep
    finally:
        store.release(owner)
    outcome.elsewhere = len(pending) - outcome.done - outcome.failed
    outcome.seconds = time.perf_counter() - start
    return outcome
