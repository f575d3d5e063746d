"""Sweep speed-up: the same study on 2 local worker processes against 1, measured in one run.

    python bench/bench_sweep.py [--data CSV] [--seeds 10] [--pmax 4] [--repeats 2]

The study: GA runs (sae, n = 3, c = 3, default GA settings, exact reference
when cheap) for p = 1…pmax and the given number of seeds: 40 runs by default,
on datasets/synthetic_cycle.csv. Each worker count runs the whole study into a
fresh database, ``--repeats`` times alternately; the best wall time of each is
kept (the machine may be shared). Prints both times, the speed-up, the cores
the workers actually obtained (their CPU seconds per wall second: well below
2 with two workers means other processes held the cores), and checks that both
databases hold the same results.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

from groupfit.sweep.config import read_study
from groupfit.sweep.executors import LocalExecutor
from groupfit.sweep.store import StudyStore
from groupfit.sweep.study import run_study

ROOT = Path(__file__).resolve().parents[1]


def write_study(folder: Path, data: Path, seeds: int, pmax: int) -> Path:
    config = folder / "bench_sweep.toml"
    config.write_text(
        f'[data]\npath = "{data.resolve().as_posix()}"\n'
        f'[grid]\np = {{start = 1, stop = {pmax}}}\nsearch = "ga"\n'
        f"[ga]\nseed = {{start = 0, stop = {seeds - 1}}}\n",
        encoding="utf-8",
    )
    return config


def children_cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed_sweep(config: Path, db: Path, workers: int) -> tuple[float, float, dict]:
    """Wall seconds, cores the workers obtained (their CPU seconds per wall second), results."""
    study = read_study(config)
    with StudyStore(db) as store:
        cpu = children_cpu_seconds()
        start = time.perf_counter()
        outcome = run_study(study, store, LocalExecutor(workers))
        seconds = time.perf_counter() - start
        cores = (children_cpu_seconds() - cpu) / seconds
        results = {row["run_hash"]: (row["breaks"], row["objective"]) for row in store.rows()}
    assert outcome.done == len(study.runs) and outcome.failed == 0
    return seconds, cores, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=ROOT / "datasets" / "synthetic_cycle.csv")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--pmax", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        config = write_study(folder, args.data, args.seeds, args.pmax)
        runs = len(read_study(config).runs)
        best = {1: float("inf"), 2: float("inf")}
        results = {}
        for repeat in range(args.repeats):
            for workers in (1, 2):
                seconds, cores, results[workers] = timed_sweep(config, folder / f"w{workers}-{repeat}.sqlite", workers)
                best[workers] = min(best[workers], seconds)
                print(
                    f"repeat {repeat + 1}: {workers} worker{'s' if workers > 1 else ''}: {seconds:.2f} s, "
                    f"the workers got {cores:.2f} cores",
                    flush=True,
                )
    same = results[1] == results[2]
    print(
        f"\n{runs} runs on {args.data.name}: 1 worker {best[1]:.2f} s, 2 workers {best[2]:.2f} s, "
        f"speed-up {best[1] / best[2]:.2f}x; same results: {same}"
    )


if __name__ == "__main__":
    main()
