"""Exact solver against ruptures' Dynp(model="linear"), same data, same run.

    python bench/bench_exact.py [--sizes 200 1000] [--ruptures-max 1000] [--large 10000]

M = 5 coefficients (4 sensors + intercept), p = 4, n = 0, sse, minimum group
size h = 16 (c = 3). Prints one row per N: both solvers' breaks, seconds and the
time ratio measured in this run, then the exact solver alone at --large.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact


def piecewise_data(N: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(N, 4)).cumsum(axis=0) * 0.1
    regime = np.minimum(np.arange(N) * 5 // N, 4)
    beta = rng.normal(size=(5, 4))
    return X, np.einsum("nk,nk->n", X, beta[regime]) + rng.normal(size=N) * 0.2


def run_exact(X, y, p=4, h=16):
    start = time.perf_counter()
    result = solve_exact(SegmentCost(X, y, n=0, objective="sse"), Constraints(len(y), 0, h), p)
    return result.breaks[p], result.objective[p], time.perf_counter() - start


def run_ruptures(X, y, p=4, h=16):
    import ruptures as rpt

    signal = np.column_stack([y, np.ones(len(y)), X])
    start = time.perf_counter()
    breaks = rpt.Dynp(model="linear", min_size=h, jump=1).fit(signal).predict(n_bkps=p)[:-1]
    return breaks, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000, 3000])
    parser.add_argument("--ruptures-max", type=int, default=1000, help="largest N also run through ruptures")
    parser.add_argument("--large", type=int, default=10_000)
    args = parser.parse_args()
    print(f"{'N':>6} {'groupfit s':>11} {'ruptures s':>11} {'ratio':>7}  same breaks  breaks")
    for N in args.sizes:
        X, y = piecewise_data(N)
        breaks, _, seconds = run_exact(X, y)
        if N <= args.ruptures_max:
            reference, reference_seconds = run_ruptures(X, y)
            print(
                f"{N:>6} {seconds:>11.3f} {reference_seconds:>11.2f} {reference_seconds / seconds:>7.0f}  "
                f"{str(reference == breaks):>11}  {breaks}"
            )
        else:
            print(f"{N:>6} {seconds:>11.3f} {'-':>11} {'-':>7}  {'-':>11}  {breaks}")
    if args.large:
        X, y = piecewise_data(args.large)
        breaks, _, seconds = run_exact(X, y)
        print(f"exact sse at N = {args.large}: {seconds:.1f} s, breaks {breaks}")


if __name__ == "__main__":
    main()
