"""GA against the exact optimum: success rate, evaluations and seconds to reach it.

    python bench/bench_ga.py [--data CSV --temps T1,T2,...] [--pmax 6] [--seeds 20]

For each p: over the seeds, how many runs end within 0.1 % of the exact
optimum, the evaluations (break vectors scored) until the best individual first
came within 0.1 % (median and worst over the runs that got there), the seconds
of those whole runs, and the worst gap of any run. Without --data it runs on the lumped thermal network on the paper's
duty cycle (300 samples, 4 sensors), data seeds 0-4.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from groupfit.data import load_run
from groupfit.data_options import split_names
from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search.exact import solve_exact
from groupfit.search.ga import GeneticSearch
from groupfit.synthetic import simulate_lumped

TOLERANCE = 1e-3


def runs(args):
    if args.data:
        run = load_run(args.data, temps=split_names(args.temps))
        yield run.name, run.temps, run.error
        return
    for seed in range(5):
        frame = simulate_lumped({"seed": seed})
        yield f"lumped seed {seed}", frame[["T1", "T2", "T3", "T4"]].to_numpy(), frame["error_um"].to_numpy()


def reach(result, target):
    """Evaluations when the best first came within tolerance (None if it never did)."""
    for value, evaluations in zip(result.history, result.evaluations_history):
        if value <= target:
            return evaluations
    return result.evaluations if result.objective <= target else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data")
    parser.add_argument("--temps")
    parser.add_argument("--objective", default="sae", choices=("sae", "sse"))
    parser.add_argument("--pmax", type=int, default=6)
    parser.add_argument("--seeds", type=int, default=20)
    args = parser.parse_args()
    print(
        f"{'run':<16} {'p':>2} {'within 0.1%':>11} {'evals med':>9} {'evals max':>9} "
        f"{'run s med':>9} {'run s max':>9} {'worst gap %':>11}"
    )
    for name, X, y in runs(args):
        constraints = Constraints.for_model(len(y), 3, 3.0, X.shape[1] + 1)
        exact = solve_exact(SegmentCost(X, y, n=3, objective=args.objective), constraints, args.pmax)
        for p in range(1, args.pmax + 1):
            target = exact.objective[p] * (1 + TOLERANCE)
            hits, evaluations, seconds, gaps = 0, [], [], []
            for seed in range(args.seeds):
                start = time.perf_counter()
                result = GeneticSearch(seed=seed).run(SegmentCost(X, y, n=3, objective=args.objective), constraints, p)
                elapsed = time.perf_counter() - start
                gaps.append(100 * (result.objective - exact.objective[p]) / exact.objective[p])
                reached = reach(result, target)
                if result.objective <= target:
                    hits += 1
                if reached is not None:
                    evaluations.append(reached)
                    seconds.append(elapsed)
            med = lambda v: f"{np.median(v):.0f}" if v else "-"  # noqa: E731
            print(
                f"{name:<16} {p:>2} {hits:>8}/{args.seeds:<2} {med(evaluations):>9} "
                f"{(max(evaluations) if evaluations else '-'):>9} "
                f"{(np.median(seconds) if seconds else float('nan')):>9.2f} "
                f"{(max(seconds) if seconds else float('nan')):>9.2f} "
                f"{max(gaps):>11.3f}"
            )


if __name__ == "__main__":
    main()
