"""The next-run estimate family by family, and a calibration checked on families it was not derived on.

Run from the repository root: ``python bench/bench_next_run_families.py`` (about 4 minutes).

The calibration factor (:data:`groupfit.heldout.calibration.FACTOR`) is the median of actual / raw over the
panel of ``bench_next_run.py``. A user's machine is none of the panel's, so this bench asks how the shipped
factor does on families of pairs it was not derived on, and how well any factor could do when one family is
held out:

* ``sim_panel``, ``fe``: the panel's independent-simulator and finite-element pairs;
* ``measured``: the shared measured test cut into runs (``../shared``; skipped when absent);
* ``fresh``: the independent simulator on seeds the panel never used (40-59, and 140-145 with the error over
  the air), a held-out check of the factor;
* ``warm/cool``: a warm-up and a cool-down repeated on another day (``bench_two_conditions.py``);
* ``warm-up``: one warm-up cut into 60 % → 40 % (``bench_warmup_cuts.py``).

Per family: the median of actual / raw, the spread of log(actual / raw), the share within a factor 2 with the
shipped factor, the share inside the printed range, and the share whose chosen model is within 1.5× of the best
p. Then, leave one family out: the factor derived (median of actual / raw) on the others and the share within a
factor 2 it gives the family left out; and the share over all pairs with a few constant factors.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import next_run_panel as panel  # noqa: E402
from bench_two_conditions import warm_cool_pair  # noqa: E402
from bench_warmup_cuts import warmup_cut  # noqa: E402

from groupfit.heldout import calibration  # noqa: E402

FRESH_SEEDS = range(40, 60)
FRESH_RISES_SEEDS = range(140, 146)
"""Seeds of the independent machine the panel never used (its own: 0-13, and 100-105 over the air)."""


def families(quick: bool) -> dict[str, list]:
    """Every family's pairs (a few of each with ``quick``)."""
    k = 3 if quick else None
    simulator = panel.simulator_pairs()
    found = {
        "sim_panel": simulator[:k],
        "fe": panel.fe_pairs()[:k],
        "measured": [] if quick else panel.measured_pairs(),
        "fresh": panel.simulator_pairs(FRESH_SEEDS[:k], FRESH_RISES_SEEDS[:k]),
        "warm/cool": [warm_cool_pair(seed) for seed in range(200, 230)][:k],
        "warm-up": [warmup_cut(seed) for seed in range(300, 320)][:k],
    }
    return {name: pairs for name, pairs in found.items() if pairs}


def within(rows: list[dict], factor: float) -> float:
    ratio = np.array([r["actual_um"] / (factor * r["raw_um"]) for r in rows])
    return float(np.mean((ratio >= 0.5) & (ratio <= 2.0)))


def covered(rows: list[dict]) -> float:
    """The share of pairs whose actual RMS lies inside the printed range."""
    ranges = [calibration.expected(r["raw_um"], unseen_condition=r["unseen_condition"])[1] for r in rows]
    return float(np.mean([low <= r["actual_um"] <= high for r, (low, high) in zip(rows, ranges)]))


def log_ratio(rows: list[dict]) -> np.ndarray:
    return np.log([r["actual_um"] / r["raw_um"] for r in rows])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="three pairs of each family")
    args = parser.parse_args()
    rows = {name: [panel.score_pair(pair) for pair in pairs] for name, pairs in families(args.quick).items()}
    factor = calibration.FACTOR
    print(
        f"{'family':<10} {'pairs':>5} {'actual/raw':>10} {'sd log':>6} {'in [0.5, 2]':>11} {'in range':>8} "
        f"{'chosen ok':>9}"
    )
    for name, scored in rows.items():
        chosen = np.mean([r["within_chosen"] for r in scored])
        logs = log_ratio(scored)
        print(
            f"{name:<10} {len(scored):>5} {np.exp(np.median(logs)):>10.2f} {logs.std():>6.2f} "
            f"{100 * within(scored, factor):>10.0f}% {100 * covered(scored):>7.0f}% {100 * chosen:>8.0f}%"
        )
    every = [r for scored in rows.values() for r in scored]
    share = 100 * within(every, factor)
    print(
        f"all {len(every)} pairs with the shipped factor {factor:.3g}: in [0.5, 2] {share:.0f} %, inside the printed "
        f"range {100 * covered(every):.0f} %"
    )
    print("\nleave one family out (factor: median of actual / raw over the other families' pairs)")
    for name, scored in rows.items():
        others = np.concatenate([log_ratio(r) for other, r in rows.items() if other != name])
        derived = float(np.exp(np.median(others)))
        print(f"  {name:<10} factor {derived:.3g}: in [0.5, 2] {100 * within(scored, derived):.0f} %")
    print("\nevery pair with a constant factor:")
    for constant in (1.0, factor, 2.0, 2.5, 3.0):
        shares = " ".join(f"{name} {100 * within(scored, constant):.0f}%" for name, scored in rows.items())
        print(f"  {constant:.3g}: all {100 * within(every, constant):.0f} %  ({shares})")


if __name__ == "__main__":
    main()
