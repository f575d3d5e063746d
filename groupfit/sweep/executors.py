"""Where the runs of a study execute: local processes or a Dask cluster.

Both executors take run specifications and yield ``(run, result)`` pairs as
runs finish, in whatever order they finish; the calling process alone writes
the results. Each run is :func:`groupfit.sweep.runs.execute_run`, the same pure
function everywhere, so a study gives the same rows on either executor.
"""

from __future__ import annotations

import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Iterator, Sequence

from groupfit.errors import InputError, first_line
from groupfit.sweep.config import RunSpec
from groupfit.sweep.runs import execute_run

PARENT_CHECK_SECONDS = 1.0


def failed_result(message: str) -> dict:
    """The result of a run whose worker could not return one."""
    return {"status": "failed", "error": message, "timings": {}, "worker": None}


class LocalExecutor:
    """Runs on ``workers`` local processes (:class:`concurrent.futures.ProcessPoolExecutor`).

    Each worker uses one BLAS thread, so K workers use K cores, and exits by
    itself if the study process dies (a killed study leaves no workers behind).
    """

    name = "local"

    def __init__(self, workers: int | None = None):
        if workers is not None and workers < 1:
            raise InputError(f"--workers {workers}: give 1 or more worker processes")
        self.workers = workers or os.cpu_count() or 1

    def describe(self) -> str:
        return f"{self.workers} local process{'es' if self.workers > 1 else ''}"

    def run(self, runs: Sequence[RunSpec]) -> Iterator[tuple[RunSpec, dict]]:
        if not runs:
            return
        pool = ProcessPoolExecutor(
            max_workers=min(self.workers, len(runs)), initializer=prepare_worker, initargs=(os.getpid(),)
        )
        try:
            futures = {pool.submit(execute_run, run.spec, run.path): run for run in runs}
            for future in as_completed(futures):
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - a worker that died takes only its runs
                    result = failed_result(f"worker process failed: {type(exc).__name__}: {exc}")
                yield futures[future], result
        finally:
            pool.shutdown(wait=True, cancel_futures=True)

    def close(self) -> None:
        pass


def prepare_worker(parent_pid: int) -> None:
    """Limit BLAS to one thread and stop this worker when the study process is gone."""
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    except ImportError:  # pragma: no cover - threadpoolctl comes with scikit-learn
        pass

    def watch_parent() -> None:
        while True:
            if os.getppid() != parent_pid:
                os._exit(1)
            time.sleep(PARENT_CHECK_SECONDS)

    threading.Thread(target=watch_parent, name="groupfit-parent-watch", daemon=True).start()


def check_address(address: str) -> None:
    """Refuse a scheduler address without a host and port before trying to connect."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme in ("tcp", "tls", "ws", "wss"):
            parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise InputError(
            f"--scheduler {address}: not a Dask scheduler address ({exc}); give one like tcp://host:8786"
        ) from None


class DaskExecutor:
    """Runs on an existing Dask distributed cluster.

    Parameters
    ----------
    address : str
        The scheduler, e.g. ``tcp://host:8786``.
    connect_timeout : float
        Seconds to wait for the scheduler.

    The data files' bytes are sent to the cluster once each (workers need not
    see the study's files), and each run's hash is checked against them.
    """

    name = "dask"

    def __init__(self, address: str, connect_timeout: float = 10.0):
        try:
            from dask.distributed import Client
        except ImportError:
            raise InputError(
                '--scheduler needs Dask distributed: pip install "groupfit[dask]" (or "dask[distributed]")'
            ) from None
        self.address = address
        check_address(address)
        try:
            self.client = Client(address, timeout=f"{connect_timeout}s", set_as_default=False)
        except Exception as exc:  # noqa: BLE001 - any failure to connect is the address's fault
            raise InputError(f"--scheduler {address}: cannot reach the Dask scheduler ({first_line(exc)})") from None

    def describe(self) -> str:
        workers = self.client.scheduler_info().get("workers", {})
        threads = sum(w.get("nthreads", 1) for w in workers.values())
        return f"Dask scheduler {self.address} ({len(workers)} workers, {threads} threads)"

    def run(self, runs: Sequence[RunSpec]) -> Iterator[tuple[RunSpec, dict]]:
        from dask.distributed import as_completed as dask_as_completed

        if not runs:
            return
        contents = {}
        for path in sorted({run.path for run in runs}):
            with open(path, "rb") as stream:
                contents[path] = self.client.scatter(stream.read(), broadcast=True, hash=True)
        futures = {}
        for run in runs:
            future = self.client.submit(execute_run, run.spec, run.path, contents[run.path], pure=False)
            futures[future] = run
        try:
            for future in dask_as_completed(list(futures), loop=self.client.loop):
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - a lost worker takes only its runs
                    result = failed_result(f"Dask task failed: {type(exc).__name__}: {exc}")
                yield futures.pop(future), result
        finally:
            for future in futures:
                future.cancel()

    def close(self) -> None:
        self.client.close()
