"""Coverage of the break-position confidence intervals on synthetic data with known breaks.

Not a test: prints the share of replications whose 95 % interval covers the
true break (pooled over the breaks of each replication), for

* ``sse``, n = 0: the block bootstrap and Bai's (1997) interval (both variants);
* ``sae``, n = 3 (the paper's setting): the block bootstrap, where Bai's
  asymptotics do not apply.

Data: N samples, two regressors (smooth AR(1) signals, like slowly varying
temperatures, plus white noise), an intercept, p true breaks at fixed
fractions of the run; the coefficient vector changes at each break and the
errors are AR(1) (coefficient rho). Regime changes happen after sample s0;
a model with soft offset n switches service at b − n, so its true hard break
is b0 = s0 + n (the script also reports coverage of s0 and the mean shift
b̂ − s0, to show that).

    python bench/bench_break_intervals.py                 # 200 replications, B = 199 (about 10 minutes)
    python bench/bench_break_intervals.py --reps 20 --boot 99   # quick look
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from groupfit.grouping import Constraints
from groupfit.inference.bootstrap import bootstrap_break_intervals
from groupfit.inference.break_intervals import bai_intervals
from groupfit.objective import SegmentCost, design_matrix
from groupfit.search.exact import solve_exact

COEFFICIENTS = np.array([[0.0, 1.0, 0.5], [1.0, 0.4, 0.9], [0.2, 1.1, 0.2]])
"""Intercept and two slopes of each regime."""


def synthetic(rng: np.random.Generator, n_samples: int, true_changes, rho: float, sigma: float):
    """Regressors, response: regime j+1 starts after sample true_changes[j]."""
    smooth = np.zeros((n_samples, 2))
    shocks = rng.normal(size=(n_samples, 2))
    for i in range(1, n_samples):
        smooth[i] = 0.8 * smooth[i - 1] + shocks[i]
    X = smooth / smooth.std(axis=0) + 0.5 * rng.normal(size=(n_samples, 2))
    noise = np.zeros(n_samples)
    innovations = rng.normal(scale=sigma * np.sqrt(1 - rho**2), size=n_samples)
    noise[0] = rng.normal(scale=sigma)
    for i in range(1, n_samples):
        noise[i] = rho * noise[i - 1] + innovations[i]
    regime = np.searchsorted(np.asarray(true_changes), np.arange(1, n_samples + 1), side="left")
    y = np.einsum("ij,ij->i", design_matrix(X, fit_intercept=True), COEFFICIENTS[regime]) + noise
    return X, y


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=200, help="replications (default 200)")
    parser.add_argument("--boot", type=int, default=199, help="bootstrap replicates each (default 199)")
    parser.add_argument("--samples", type=int, default=150, help="N (default 150)")
    parser.add_argument("--rho", type=float, default=0.3, help="AR(1) coefficient of the errors (default 0.3)")
    parser.add_argument("--sigma", type=float, default=0.6, help="error standard deviation (default 0.6)")
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--cases", default="sse0,sae3", help="comma list of sse0, sae3")
    args = parser.parse_args()

    n_samples = args.samples
    true_changes = [n_samples // 3, 2 * n_samples // 3]
    p = len(true_changes)
    print(
        f"N = {n_samples}, true regime changes after samples {true_changes}, AR(1) errors rho = {args.rho}, "
        f"sigma = {args.sigma}; {args.reps} replications, B = {args.boot}, level 0.95"
    )
    for case in args.cases.split(","):
        objective, n = case[:3], int(case[3:])
        truth = np.array(true_changes) + n
        covered = {"bootstrap": 0, "bai het": 0, "bai hom": 0, "bootstrap vs s0": 0}
        counted = {key: 0 for key in covered}
        widths, shifts = [], []
        start = time.perf_counter()
        for rep in range(args.reps):
            rng = np.random.default_rng([args.seed, rep])
            X, y = synthetic(rng, n_samples, true_changes, args.rho, args.sigma)
            cost = SegmentCost(X, y, n=n, objective=objective, fit_intercept=True)
            breaks = solve_exact(cost, Constraints.for_model(n_samples, n, 3.0, 3), p).breaks[p]
            shifts.extend(np.array(breaks) - np.array(true_changes))
            boot = bootstrap_break_intervals(
                X, y, breaks, n=n, c=3.0, objective=objective, level=0.95, n_boot=args.boot, seed=rep
            )
            for interval, b0, s0 in zip(boot.intervals, truth, true_changes):
                covered["bootstrap"] += interval.lower <= b0 <= interval.upper
                covered["bootstrap vs s0"] += interval.lower <= s0 <= interval.upper
                counted["bootstrap"] += 1
                counted["bootstrap vs s0"] += 1
                widths.append(interval.upper - interval.lower)
            if objective == "sse" and n == 0:
                design = design_matrix(X, fit_intercept=True)
                for key, het in (("bai het", True), ("bai hom", False)):
                    for interval, b0 in zip(bai_intervals(design, y, breaks, 0.95, het_reg=het, het_err=het), truth):
                        if interval.lower is not None:
                            covered[key] += interval.lower <= b0 <= interval.upper
                            counted[key] += 1
        seconds = time.perf_counter() - start
        print(f"\n{objective}, n = {n} (true hard breaks {truth.tolist()}), {seconds:.0f} s")
        print(f"  mean shift b̂ − s0: {np.mean(shifts):+.2f} samples (sd {np.std(shifts):.2f})")
        for key in covered:
            if counted[key]:
                share = covered[key] / counted[key]
                print(f"  {key:16s} coverage {100 * share:5.1f} %  ({covered[key]}/{counted[key]} break intervals)")
        print(f"  bootstrap interval width: median {np.median(widths):.0f}, mean {np.mean(widths):.1f} samples")


if __name__ == "__main__":
    main()
