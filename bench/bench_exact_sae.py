"""The exact search on sae against the same search on sse, same data, same run.

    python bench/bench_exact_sae.py [--sizes 1000 3000 10000] [--inputs 4 16] [--measured CSV] [--single-p]

Each solve runs in a fresh process, one after another, so that its seconds and
its peak memory (the process's largest resident set, less that of a process
that only built the data) are its own. The machine may be shared: read the
ratio sae/sse of one row (both measured in the same run, seconds apart), not
the seconds. Data: the synthetic run of bench_exact.py (random-walk inputs,
5 regimes, so 4 true breaks, noise 0.2), p = 4, n = 0, c = 3; or with
--measured the first N rows of a measured run (its first `--inputs` sensor
columns t1_C…, error disp_ch3_um, n = 3). --single-p asks only for p = 4
(as `fit` certifying the GA does); by default every p ≤ 4 is answered.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact

P = 4


def synthetic(N: int, n_inputs: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(N, n_inputs)).cumsum(axis=0) * 0.1
    regime = np.minimum(np.arange(N) * 5 // N, 4)
    beta = rng.normal(size=(5, n_inputs))
    return X, np.einsum("nk,nk->n", X, beta[regime]) + rng.normal(size=N) * 0.2


def measured(path: str, N: int, n_inputs: int):
    import pandas as pd

    frame = pd.read_csv(path, nrows=N)
    X = frame[[f"t{i}_C" for i in range(1, n_inputs + 1)]].to_numpy()
    return X - X[0], frame["disp_ch3_um"].to_numpy()


def one(args) -> dict:
    """Run one solve in this process; report seconds and the peak resident set."""
    X, y = measured(args.measured, args.N, args.k) if args.measured else synthetic(args.N, args.k)
    n = 3 if args.measured else 0
    constraints = Constraints.for_model(len(y), n, 3.0, args.k + 1)
    report = {"base_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
    if args.objective != "none":
        cost = SegmentCost(X, y, n=n, objective=args.objective)
        start = time.perf_counter()
        result = solve_exact(cost, constraints, P, every_p=not args.single_p)
        report.update(
            seconds=time.perf_counter() - start,
            breaks=result.breaks[P],
            objective=result.objective[P],
            pruning=result.pruning,
        )
    report["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return report


def spawn(N: int, k: int, objective: str, args) -> dict:
    command = [sys.executable, __file__, "--one", str(N), str(k), objective]
    if args.measured:
        command += ["--measured", args.measured]
    if args.single_p:
        command.append("--single-p")
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 3000, 10_000])
    parser.add_argument("--inputs", type=int, nargs="+", default=[4, 16], help="inputs per group (M = inputs + 1)")
    parser.add_argument("--measured", metavar="CSV", help="first N rows of a measured run instead of synthetic data")
    parser.add_argument("--single-p", action="store_true", help="answer p = 4 only (as fit's certification)")
    parser.add_argument("--one", nargs=3, metavar=("N", "INPUTS", "OBJECTIVE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        args.N, args.k, args.objective = int(args.one[0]), int(args.one[1]), args.one[2]
        print(json.dumps(one(args)))
        return
    header = f"{'N':>6} {'M':>3} {'sse s':>8} {'sae s':>8} {'ratio':>6} {'sse MB':>7} {'sae MB':>7}"
    print(header + "  left after the bounds, costed exactly")
    for k in args.inputs:
        for N in args.sizes:
            base = spawn(N, k, "none", args)["peak_mb"]
            sse = spawn(N, k, "sse", args)
            sae = spawn(N, k, "sae", args)
            pruning = sae["pruning"]
            left = f"{pruning['left']} costed {pruning['costed']} of {pruning['segments']}" if pruning else "-"
            ratio = sae["seconds"] / sse["seconds"]
            print(
                f"{N:>6} {k + 1:>3} {sse['seconds']:>8.2f} {sae['seconds']:>8.2f} {ratio:>6.1f} "
                f"{sse['peak_mb'] - base:>7.0f} {sae['peak_mb'] - base:>7.0f}  {left}",
                flush=True,
            )


if __name__ == "__main__":
    main()
