"""How the break search scales with the number of samples N and of sensors M.

    python bench/bench_scale.py [--quick] [--sizes 300 1000 …] [--sensors 4 8 …]

Data: smooth random temperature walks and an error that is linear in them with
coefficients changing in 5 regimes, p = 4 breaks searched, n = 3, c = 3.
M below counts the intercept (M = sensors + 1).

Part 1, N at M = 5: seconds to build the segment-cost prefix sums, seconds per
GA generation (population 60, 20 generations without early stop or local
search, the segment-cost cache on) for sse and sae, and the exact dynamic
programme's seconds for sse and sae up to where it is practical. Part 2,
sensors at fixed N: the same GA figures and prefix memory, and the exact sse
time at N = 1000. The exponent of each column is the slope of a least-squares
line through (log N, log seconds) over the points with N ≥ 1000 (M ≥ 9 for
part 2; every point for exact sae), the small sizes being dominated by fixed
overheads. Part 3 (not with --quick): the GA at N = 100 000 and 64 sensors.
Part 4: the local search that closes every GA run of ``fit`` (one break, sae,
M = 5) at N and 10 N, coarse to fine as ``fit`` runs it and trying every
position (the baseline, measured in the same run): seconds, the peak memory
allocated (traced), their ratios, and whether both find the same break. The
sae cost holds its residuals in blocks of bounded size (before them, a day at
1 s asked for 51 GiB); every position costs a residual pass, so trying them all
is quadratic in N (8 640 → 86 400: 5.4 → 142 s on a busy 2-core machine).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from groupfit.grouping import Constraints
from groupfit.objective import SAE_BLOCK_ELEMENTS, SegmentCost
from groupfit.search import polish
from groupfit.search.exact import solve_exact
from groupfit.search.ga import CachedObjective, GeneticSearch
from groupfit.search.polish import polish_breaks

P = 4
N_SOFT = 3
C = 3.0
GENERATIONS = 20
POPULATION = 60


def regime_data(n_samples: int, n_sensors: int, seed: int = 0):
    """Smooth temperature walks; error linear in them, coefficients changing in 5 regimes."""
    rng = np.random.default_rng(seed)
    steps = rng.normal(size=(n_samples + 50, n_sensors))
    kernel = np.ones(50) / 50
    X = np.column_stack([np.convolve(steps[:, j], kernel, mode="valid")[:n_samples] for j in range(n_sensors)])
    X = X.cumsum(axis=0) * 0.05
    regime = np.minimum(np.arange(n_samples) * 5 // n_samples, 4)
    beta = rng.normal(size=(5, n_sensors))
    y = np.einsum("nk,nk->n", X, beta[regime]) + 0.05 * rng.normal(size=n_samples)
    return X, y


def timed(function, *args, **kwargs):
    start = time.perf_counter()
    value = function(*args, **kwargs)
    return value, time.perf_counter() - start


def ga_seconds_per_generation(X, y, objective: str) -> tuple[float, float]:
    """(seconds per generation, seconds to build the prefix sums) of a fixed-length GA run."""
    cost, build = timed(SegmentCost, X, y, n=N_SOFT, objective=objective)
    constraints = Constraints.for_model(len(y), N_SOFT, C, cost.n_coef)
    search = GeneticSearch(
        population_size=POPULATION, max_generations=GENERATIONS, stall_generations=GENERATIONS + 1, polish=False, seed=0
    )
    result = search.run(cost, constraints, P)
    return result.seconds / result.generations, build


def exact_seconds(X, y, objective: str) -> float:
    cost = SegmentCost(X, y, n=N_SOFT, objective=objective)
    constraints = Constraints.for_model(len(y), N_SOFT, C, cost.n_coef)
    _, seconds = timed(solve_exact, cost, constraints, P)
    return seconds


def prefix_megabytes(n_samples: int, n_coef: int) -> float:
    """Memory of the prefix sums: (N + 1) × (M + 1)(M + 2)/2 doubles."""
    return (n_samples + 1) * (n_coef + 1) * (n_coef + 2) / 2 * 8 / 1e6


def exponent(sizes, seconds, smallest) -> str:
    points = [(s, t) for s, t in zip(sizes, seconds) if t is not None and s >= smallest]
    if len(points) < 2:
        return "-"
    slope = np.polyfit(np.log([s for s, _ in points]), np.log([t for _, t in points]), 1)[0]
    return f"{slope:.2f}"


def fmt(value, digits=4) -> str:
    return "-" if value is None else f"{value:.{digits}g}"


def part_n(sizes, exact_sse_max, exact_sae_max) -> None:
    print(f"Part 1: N at M = 5 (4 sensors + intercept), p = {P}, GA population {POPULATION}")
    header = (
        f"{'N':>7} {'prefix s':>9} {'prefix MB':>9} {'GA sse s/gen':>12} {'GA sae s/gen':>12} "
        f"{'exact sse s':>11} {'exact sae s':>11}"
    )
    print(header)
    columns = {k: [] for k in ("prefix", "ga_sse", "ga_sae", "exact_sse", "exact_sae")}
    for N in sizes:
        X, y = regime_data(N, 4)
        ga_sse, build = ga_seconds_per_generation(X, y, "sse")
        ga_sae, _ = ga_seconds_per_generation(X, y, "sae")
        exact_sse = exact_seconds(X, y, "sse") if N <= exact_sse_max else None
        exact_sae = exact_seconds(X, y, "sae") if N <= exact_sae_max else None
        for key, value in zip(columns, (build, ga_sse, ga_sae, exact_sse, exact_sae)):
            columns[key].append(value)
        print(
            f"{N:>7} {build:>9.4f} {prefix_megabytes(N, 5):>9.1f} {ga_sse:>12.4f} {ga_sae:>12.4f} "
            f"{fmt(exact_sse):>11} {fmt(exact_sae):>11}",
            flush=True,
        )
    print(
        f"{'slope':>7} {exponent(sizes, columns['prefix'], 1000):>9} {'':>9} "
        f"{exponent(sizes, columns['ga_sse'], 1000):>12} {exponent(sizes, columns['ga_sae'], 1000):>12} "
        f"{exponent(sizes, columns['exact_sse'], 1000):>11} {exponent(sizes, columns['exact_sae'], 300):>11}"
    )


def part_m(sensor_counts, n_samples, exact_n, exact_max_sensors) -> None:
    print(f"\nPart 2: sensors at N = {n_samples} (exact sse at N = {exact_n}), p = {P}")
    print(
        f"{'sensors':>7} {'M':>3} {'prefix s':>9} {'prefix MB':>9} {'GA sse s/gen':>12} {'GA sae s/gen':>12} "
        f"{'exact sse s':>11}"
    )
    columns = {k: [] for k in ("prefix", "ga_sse", "ga_sae", "exact_sse")}
    for k in sensor_counts:
        X, y = regime_data(n_samples, k)
        ga_sse, build = ga_seconds_per_generation(X, y, "sse")
        ga_sae, _ = ga_seconds_per_generation(X, y, "sae")
        exact = None
        if k <= exact_max_sensors:
            Xe, ye = regime_data(exact_n, k)
            exact = exact_seconds(Xe, ye, "sse")
        for key, value in zip(columns, (build, ga_sse, ga_sae, exact)):
            columns[key].append(value)
        print(
            f"{k:>7} {k + 1:>3} {build:>9.4f} {prefix_megabytes(n_samples, k + 1):>9.1f} {ga_sse:>12.4f} "
            f"{ga_sae:>12.4f} {fmt(exact):>11}",
            flush=True,
        )
    ms = [k + 1 for k in sensor_counts]
    print(
        f"{'slope':>7} {'':>3} {exponent(ms, columns['prefix'], 9):>9} {'':>9} "
        f"{exponent(ms, columns['ga_sse'], 9):>12} "
        f"{exponent(ms, columns['ga_sae'], 9):>12} {exponent(ms, columns['exact_sse'], 9):>11}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes: about a minute")
    parser.add_argument("--sizes", type=int, nargs="+")
    parser.add_argument("--sensors", type=int, nargs="+")
    parser.add_argument("--m-samples", type=int, help="N of part 2")
    parser.add_argument("--exact-sse-max", type=int, help="largest N for the exact sse search")
    parser.add_argument("--exact-sae-max", type=int, help="largest N for the exact sae search")
    args = parser.parse_args()
    if args.quick:
        sizes, sensors, m_samples, sse_max, sae_max = [300, 600, 1000, 3000, 10000], [4, 8, 16, 32], 3000, 3000, 600
    else:
        sizes, sensors, m_samples, sse_max, sae_max = (
            [300, 600, 1000, 3000, 10000, 30000, 100000],
            [4, 8, 16, 32, 64],
            10000,
            10000,
            1000,
        )
    part_n(args.sizes or sizes, args.exact_sse_max or sse_max, args.exact_sae_max or sae_max)
    part_m(args.sensors or sensors, args.m_samples or m_samples, 1000, 16 if args.quick else 32)
    if not args.quick:
        corner(100_000, 64)
    polish_memory(8_640 if not args.quick else 2_000)


def corner(n_samples: int, n_sensors: int) -> None:
    """The largest case: only the GA is practical; prefix sums of (N+1)(M+1)(M+2)/2 doubles."""
    print(
        f"\nPart 3: N = {n_samples}, {n_sensors} sensors (M = {n_sensors + 1}): "
        f"prefix sums {prefix_megabytes(n_samples, n_sensors + 1) / 1e3:.2f} GB"
    )
    X, y = regime_data(n_samples, n_sensors)
    for objective in ("sse", "sae"):
        per_generation, build = ga_seconds_per_generation(X, y, objective)
        print(f"GA {objective}: {per_generation:.3f} s per generation (prefix built in {build:.1f} s)", flush=True)


def polish_memory(n_small: int) -> None:
    """Seconds and traced peak memory of the GA's closing local search at ``n_small`` and 10× as many samples,
    coarse to fine (as ``fit`` runs it) and trying every position (the baseline), and whether both agree."""
    print(f"\nPart 4: the GA's closing local search (sae, p = 1, M = 5) at N = {n_small} and {10 * n_small}")
    figures = {}
    for n_samples in (n_small, 10 * n_small):
        X, y = regime_data(n_samples, 4)
        cost = SegmentCost(X, y, n=N_SOFT, objective="sae")
        constraints = Constraints.for_model(n_samples, N_SOFT, C, cost.n_coef)
        start = [n_samples // 3]
        found = []
        for mode, limit in (("coarse to fine", polish.COARSE_POSITIONS), ("every position", 10**12)):
            objective = CachedObjective(cost)
            default, polish.COARSE_POSITIONS = polish.COARSE_POSITIONS, limit
            tracemalloc.start()
            try:
                (breaks, value), seconds = timed(
                    polish_breaks, start, objective.totals([start])[0], objective, constraints
                )
            finally:
                polish.COARSE_POSITIONS = default
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            figures[n_samples, mode] = (seconds, peak)
            found.append((breaks, value))
            print(
                f"N = {n_samples:>7}, {mode}: {seconds:8.2f} s, peak {peak / 2**20:8.1f} MiB, breaks {breaks}",
                flush=True,
            )
        print(f"N = {n_samples:>7}: the same breaks and Rg both ways: {found[0] == found[1]}")
    for mode in ("coarse to fine", "every position"):
        (t1, m1), (t2, m2) = figures[n_small, mode], figures[10 * n_small, mode]
        print(f"{mode}: ratio 10 N / N: time {t2 / t1:.1f}, memory {m2 / m1:.1f}")
    for n_samples in (n_small, 10 * n_small):
        ratio = figures[n_samples, "every position"][0] / figures[n_samples, "coarse to fine"][0]
        print(f"N = {n_samples}: every position takes {ratio:.1f}× the time of coarse to fine")
    print(f"(residual blocks capped at {SAE_BLOCK_ELEMENTS:.3g} values; uncapped, the peak grows as N², 100× for 10 N)")


if __name__ == "__main__":
    main()
