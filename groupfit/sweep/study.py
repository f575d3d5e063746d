"""Run a study: skip the runs already done, execute the rest, record each as it finishes."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from groupfit.sweep.config import Study
from groupfit.sweep.store import StudyStore


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
    """

    db: Path
    total: int
    done: int = 0
    skipped: int = 0
    failed: int = 0
    seconds: float = 0.0
    failures: list[tuple[str, str]] = field(default_factory=list)


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
    for run, result in executor.run(pending):
        store.record(run, result, study.name)
        if result["status"] == "done":
            outcome.done += 1
        else:
            outcome.failed += 1
            outcome.failures.append((run.run_hash, result.get("error") or "unknown error"))
        if progress is not None:
            progress(1)
    outcome.seconds = time.perf_counter() - start
    return outcome
