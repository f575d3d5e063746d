"""The next-run estimate on one warm-up cut in two: the model on its first 60 %, the next run its last 40 %.

Run from the repository root: ``python bench/bench_warmup_cuts.py [--pairs 20]`` (about 20 s).

A warm-up at one speed holds no change of an operating column, so the estimate cuts the model part into blocks of
time (``docs/nextrun.md``) and notes that one condition cannot show how a new one goes. The calibration panel has no
such pair; this bench measures the family on the independent machine (``independent_machine.py``: a random machine
and workshop day; 0-1 h at rest, then one speed of 2000-6000 r/min for 5-12 h; an unsensed part driven by the air
or by the speed on two seeds of five). Each pair is scored with the panel's own scoring
(``next_run_panel.score_pair``; the last 40 % replayed after the first 60 %, as ``groupfit replay`` replays the rest
of a recording): the estimate against the actual RMS, and whether the chosen model, BIC's and the old default
p = 3 are within 1.5x of the best of p = 0-3 on the last 40 %.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import independent_machine as machine  # noqa: E402
import next_run_panel as panel  # noqa: E402
from bench_two_conditions import hidden_part  # noqa: E402

from groupfit.heldout.nextrun import sliced  # noqa: E402

SPEEDS = (2000, 3000, 4000, 5000, 6000)
MODEL_SHARE = 0.6


def warmup_cut(seed: int) -> panel.Pair:
    """Pair ``u<seed>``: one warm-up run; the model on its first 60 %, the next run the rest of the recording."""
    rng = np.random.default_rng(seed)
    kind = machine.RANDOM_KINDS[seed % len(machine.RANDOM_KINDS)]
    period = float(rng.choice([10, 20, 30, 60]))
    tau_h = float(rng.uniform(0.4, 4.0))
    speed = float(rng.choice(SPEEDS))
    warm_h, rest_h = float(rng.uniform(5, 12)), float(rng.uniform(0, 1))
    recipe = machine._recipe(
        warm_h + rest_h, period, 2 * seed, machine._random_ambient(rng), spindle_part_tau_h=tau_h,
        pump_part_tau_h=tau_h, speed=[(rest_h, 0.0), (warm_h + 1.0, speed)],
    )  # fmt: skip
    hidden, log = hidden_part(kind, rng)
    build = machine._pair(recipe, recipe, hidden, heat_driven_only=kind == "speed", **log)
    spec = machine.ScenarioSpec(f"u{seed}_{kind if hidden else 'none'}", "one warm-up", (), build)
    scenario = spec.make()
    whole = panel.frame_run(scenario.modelling, scenario.name, scenario.temps)
    cut = int(MODEL_SHARE * whole.n_samples)
    model = sliced(whole, np.arange(cut))
    following = sliced(whole, np.arange(cut, whole.n_samples))
    return panel.make_pair(scenario.name, "warm-up", model, following, continues=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=20, help="how many pairs (seeds 300 on)")
    args = parser.parse_args()
    rows = [panel.score_pair(warmup_cut(seed)) for seed in range(300, 300 + args.pairs)]
    print(f"{'pair':<14} {'p':>2} {'expect':>8} {'actual':>8} {'ratio':>6} {'best':>4} {'bic':>3}  actual by p")
    ratios = []
    for row in rows:
        expected = panel.expected_um(row)
        ratios.append(row["actual_um"] / expected)
        by_p = " ".join(f"{v:.3g}" for v in row["actual_by_p"].values())
        print(
            f"{row['pair']:<14} {row['chosen_p']:>2} {expected:>8.3g} {row['actual_um']:>8.3g} {ratios[-1]:>6.2f} "
            f"{row['best_p']:>4} {row['bic_p']:>3}  {by_p}"
        )
    ratio = np.array(ratios)
    inside = np.mean((ratio >= 0.5) & (ratio <= 2.0))
    shares = {key: 100 * np.mean([r[f"within_{key}"] for r in rows]) for key in ("chosen", "bic", "default")}
    print(
        f"{len(rows)} pairs: actual/expected median {np.median(ratio):.2f}, in [0.5, 2]: {100 * inside:.0f} %; "
        f"within 1.5x of the best p: chosen {shares['chosen']:.0f} %, BIC {shares['bic']:.0f} %, "
        f"p = 3 {shares['default']:.0f} %"
    )


if __name__ == "__main__":
    main()
