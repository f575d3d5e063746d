"""The next-run estimate on runs of two conditions: a warm-up, then a cool-down, repeated on another day.

Run from the repository root: ``python bench/bench_two_conditions.py`` (about a minute).

A run of two conditions is the sharpest case of forward chaining (docs/nextrun.md): its first scored segment is
the first of the cool-down, fitted on the warm-up alone, and it decides both the figure and the choice. A next run
of the same programme brings no condition the model was not fitted on, so one may leave that segment out
("the first segment of a new condition is not scored when the run before it holds one condition"). This bench
builds such pairs on the independent machine (``independent_machine.py``: random machines and workshop days; the
spindle at one speed for 3-8 h, then stopped for 3-8 h; the next run the same programme, each stretch ±15 %, on
another day) and scores both rules with the panel's own scoring (``next_run_panel.score_pair``): the share of
pairs whose actual / expected lies in [0.5, 2], and the share whose chosen model is within 1.5× of the best p.
Last, the factor of such runs (:data:`groupfit.heldout.calibration.UNSEEN_CONDITION_FACTOR`, the median of
actual / raw over the pairs): derived on the even-numbered pairs and checked on the odd-numbered ones and the
other way round, beside the panel's factor for every run.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import independent_machine as machine  # noqa: E402
import next_run_panel as panel  # noqa: E402

from groupfit.heldout import calibration, nextrun  # noqa: E402

SPEEDS = (2000, 3000, 4000, 5000, 6000)


def warm_cool_pair(seed: int) -> panel.Pair:
    """Pair ``w<seed>``: a warm-up at one speed and a cool-down, then the same programme on another day."""
    rng = np.random.default_rng(seed)
    kind = machine.RANDOM_KINDS[seed % len(machine.RANDOM_KINDS)]
    period = float(rng.choice([10, 20, 30, 60, 120]))
    tau_h = float(rng.uniform(0.4, 4.0))
    speed = float(rng.choice(SPEEDS))
    warm_h, cool_h = float(rng.uniform(3, 8)), float(rng.uniform(3, 8))
    recipes = []
    for k in range(2):
        warm, cool = warm_h * rng.uniform(0.85, 1.15), cool_h * rng.uniform(0.85, 1.15)
        ambient = machine._random_ambient(rng)
        schedule = [(warm, speed), (cool + 1.0, 0.0)]
        recipes.append(
            machine._recipe(
                warm + cool, period, 2 * seed + k, ambient, spindle_part_tau_h=tau_h, pump_part_tau_h=tau_h,
                speed=schedule,
            )
        )  # fmt: skip
    hidden, log = hidden_part(kind, rng)
    build = machine._pair(*recipes, hidden, heat_driven_only=kind == "speed", **log)
    missing = kind if hidden else "none"
    spec = machine.ScenarioSpec(f"w{seed}_{missing}", "warm-up, cool-down", (), build)
    scenario = spec.make()
    model = panel.frame_run(scenario.modelling, f"{scenario.name}_model", scenario.temps)
    following = panel.frame_run(scenario.validation, f"{scenario.name}_next", scenario.temps)
    return panel.make_pair(scenario.name, "warm/cool", model, following)


def hidden_part(kind: str, rng: np.random.Generator) -> tuple[str | None, dict]:
    """The unsensed part that carries a missing effect of ``kind`` (``"ambient"``: a part driven by the air;
    ``"speed"``: a part heated by the spindle), with its gain drawn from ``rng``; ``(None, {})`` for the others,
    whose pumps and on/off spindles these one-speed runs do not simulate."""
    if kind == "ambient":
        return "U", {"extra_gains": {"U": float(rng.uniform(1.5, 4.0))}}
    if kind == "speed":
        return "S", {"extra_gains": {"S": float(rng.uniform(2.0, 5.0))}}
    return None, {}


def seen_after_one_condition(shipped):
    """``forward_folds`` less the folds of a new condition whose run before holds one condition."""

    def folds(run, starts, min_train=nextrun.MIN_TRAIN_FRACTION):
        scored = shipped(run, starts, min_train)
        codes = nextrun.segment_starts(run)[4]
        kept = [(a, b) for a, b in scored if not nextrun.leaves_one_condition([(a, b)], codes)]
        return kept or scored

    return folds


def summary(rows: list[dict], label: str, factor: float | None = None) -> None:
    """The share of ``rows`` within a factor 2 of their expected figure (``factor`` × raw for every pair when
    given, else as ``fit`` calibrates each) and the share whose chosen model is within 1.5× of the best p."""
    ratio = np.array(
        [r["actual_um"] / (factor * r["raw_um"] if factor is not None else panel.expected_um(r)) for r in rows]
    )
    inside = np.mean((ratio >= 0.5) & (ratio <= 2.0))
    chosen = np.mean([r["within_chosen"] for r in rows])
    print(
        f"{label}: {len(rows)} pairs, actual/expected median {np.median(ratio):.2f}, in [0.5, 2]: "
        f"{100 * inside:.0f} %; chosen model within 1.5x of the best p: {100 * chosen:.0f} %"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=30, help="how many pairs (seeds 200 on)")
    args = parser.parse_args()
    pairs = [warm_cool_pair(seed) for seed in range(200, 200 + args.pairs)]
    shipped = nextrun.forward_folds
    rows = {"shipped (every segment after 40 % scored)": [panel.score_pair(pair) for pair in pairs]}
    nextrun.forward_folds = seen_after_one_condition(shipped)
    try:
        rows["first cool-down segment not scored"] = [panel.score_pair(pair) for pair in pairs]
    finally:
        nextrun.forward_folds = shipped
    print(f"{'pair':<18} {'rule':<8} {'p':>2} {'expect':>8} {'actual':>8} {'ratio':>6} {'best':>4}  actual by p")
    for label, scored in rows.items():
        for row in scored:
            expected = panel.expected_um(row)
            by_p = " ".join(f"{v:.3g}" for v in row["actual_by_p"].values())
            print(
                f"{row['pair']:<18} {label[:8]:<8} {row['chosen_p']:>2} {expected:>8.3g} {row['actual_um']:>8.3g} "
                f"{row['actual_um'] / expected:>6.2f} {row['best_p']:>4}  {by_p}"
            )
    for label, scored in rows.items():
        summary(scored, label)
    shipped_rows = next(iter(rows.values()))
    flagged = [row for row in shipped_rows if row["unseen_condition"]]
    print(f"\n{len(flagged)} of {len(shipped_rows)} runs start a condition the run before never saw (their own factor)")
    summary(shipped_rows, "with the panel's factor for every run", calibration.FACTOR)
    for name, derive_on, check_on in (("even", 0, 1), ("odd", 1, 0)):
        derived = calibration.derive_calibration(
            [r["raw_um"] for r in shipped_rows[derive_on::2]], [r["actual_um"] for r in shipped_rows[derive_on::2]]
        )
        summary(shipped_rows[check_on::2], f"factor {derived['factor']:.3g} from the {name}-numbered, on the others",
                derived["factor"])  # fmt: skip
    everything = calibration.derive_calibration(
        [r["raw_um"] for r in shipped_rows], [r["actual_um"] for r in shipped_rows]
    )
    print(f"derived on all {len(shipped_rows)} (what ships as UNSEEN_CONDITION_FACTOR and its range): {everything}")


if __name__ == "__main__":
    main()
