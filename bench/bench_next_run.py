"""The next-run estimate on its calibration panel, and on the shared measured test cut into runs.

Run from the repository root: ``python bench/bench_next_run.py`` (a few minutes).
Prints, per pair (model run → next run), the raw figure, the expected RMS
(calibrated), the actual RMS of the chosen model replayed through the run-time
rule over the next run, their ratio, how many inputs the next run takes beyond
the model run's span (``out``: where ``groupfit replay`` notes that the
expected figure does not cover the run; the share in [0.5, 2] is also given
apart for the pairs that stay within it and those that leave it), and whether the chosen p, BIC's p and the
old default p = 3 are within 1.5× of the best p = 0…3 there; then the same for
the cuts of the shared measured test (``../shared``). Then derives the
calibration (:func:`groupfit.heldout.calibration.derive_calibration`) on the
even-numbered of all pairs (panel and cuts) and checks it on the odd-numbered
ones, and on all of them (the factor that ships). Then every pair again as a
log without its operating columns would give it (the estimate cuts the model
run into blocks of time), with the factor that ships. Last, leave-one-run-out on
two or three of the six FE runs against each other one: the range printed
with several runs (:data:`groupfit.heldout.calibration.SEVERAL_RUNS_RANGE`).
``--quick`` scores a small subset.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import next_run_panel as panel  # noqa: E402

from groupfit.heldout import calibration  # noqa: E402


def table(rows: list[dict], title: str) -> None:
    print(f"\n{title}")
    print(
        f"{'pair':<42} {'src':<9} {'p':>2} {'raw':>8} {'expect':>8} {'actual':>8} {'ratio':>6} {'out':>3}  "
        f"{'best':>4} {'bic':>3}  ok(ch/bic/p3)  actual by p"
    )
    for r in rows:
        expected = panel.expected_um(r)
        ratio = r["actual_um"] / expected
        by_p = " ".join(f"{v:.3g}" for v in r["actual_by_p"].values())
        ok = "".join("y" if r[k] else "." for k in ("within_chosen", "within_bic", "within_default"))
        print(
            f"{r['pair'][:42]:<42} {r['source'][:9]:<9} {r['chosen_p']:>2} {r['raw_um']:>8.3g} {expected:>8.3g} "
            f"{r['actual_um']:>8.3g} {ratio:>6.2f} {len(r['inputs_beyond_span']):>3}  "
            f"{r['best_p']:>4} {r['bic_p']:>3}  {ok:^13}  {by_p}"
        )
    summary(rows, calibration.FACTOR, "all")
    within_span(rows, calibration.FACTOR)
    undecided_references(rows, calibration.FACTOR)


def undecided_references(rows: list[dict], factor: float) -> None:
    """The pairs whose model run cannot tell the two references apart (``fit`` then notes what a day at another
    air level costs): their actual / expected, beside the rest's."""
    undecided = [(r.get("reference_choice") or {}).get("told_apart") is False for r in rows]
    noted = [r for r, flag in zip(rows, undecided) if flag]
    if not noted:
        return
    ratios = ", ".join(f"{r['pair']} {r['actual_um'] / panel.expected_um(r, factor):.2f}" for r in noted)
    others = np.array([r["actual_um"] / panel.expected_um(r, factor) for r, flag in zip(rows, undecided) if not flag])
    print(
        f"  the reference note (the run cannot tell the references apart): {len(noted)} pairs, actual / expected "
        f"{ratios}; the other {len(others)} pairs: beyond 2 on {int(np.sum(others > 2))}"
    )


def within_span(rows: list[dict], factor: float) -> None:
    """The share in [0.5, 2] apart for the pairs whose next run stays within the model run's span and for those
    it leaves (where ``groupfit replay`` notes that the expected figure does not cover the run)."""
    for label, part in (
        ("next run within the modelling range", [r for r in rows if not r["inputs_beyond_span"]]),
        ("next run beyond it (replay notes it)", [r for r in rows if r["inputs_beyond_span"]]),
    ):
        if part:
            ratio = np.array([r["actual_um"] / panel.expected_um(r, factor) for r in part])
            inside = np.mean((ratio >= 0.5) & (ratio <= 2.0))
            print(f"  {label}: {len(part)} pairs, in [0.5, 2]: {100 * inside:.0f} %")


def summary(rows: list[dict], factor: float, label: str) -> None:
    if not rows:
        return
    ratio = np.array([r["actual_um"] / panel.expected_um(r, factor) for r in rows])
    inside = np.mean((ratio >= 0.5) & (ratio <= 2.0))
    ranges = [calibration.calibrated(unseen_condition=r.get("unseen_condition", False))[1] for r in rows]
    in_range = np.mean([low <= x <= high for x, (low, high) in zip(ratio, ranges)])
    shares = {k: np.mean([r[k] for r in rows]) for k in ("within_chosen", "within_bic", "within_default")}
    print(
        f"{label}: {len(rows)} pairs, factor {factor:.3g}: ratio actual/expected median {np.median(ratio):.2f}, "
        f"in [0.5, 2]: {100 * inside:.0f} %, inside the printed range: {100 * in_range:.0f} %; within 1.5x of the "
        f"best p: chosen {100 * shares['within_chosen']:.0f} %, BIC {100 * shares['within_bic']:.0f} %, "
        f"p = 3 {100 * shares['within_default']:.0f} %"
    )


def ceiling(rows: list[dict]) -> str:
    """The largest share of pairs any one factor could bring within [0.5, 2] of the actual, and that factor.

    It bounds every constant calibration of the raw figure: a share below the goal here means the spread of
    actual / raw, not the choice of factor, is what misses.
    """
    ratio = np.array([r["actual_um"] / r["raw_um"] for r in rows])
    factors = np.exp(np.linspace(np.log(ratio.min()), np.log(ratio.max()), 2001))
    shares = [np.mean((ratio >= 0.5 * f) & (ratio <= 2.0 * f)) for f in factors]
    best = int(np.argmax(shares))
    return (
        f"the best any constant factor can do: {100 * shares[best]:.0f} % of the pairs within [0.5, 2] "
        f"(factor {factors[best]:.3g}); spread of log(actual / raw): sd {np.std(np.log(ratio)):.2f}"
    )


def several_summary(rows: list[dict]) -> None:
    """Leave-one-run-out on several FE runs: the estimate against the next run, per number of runs."""
    print("\nseveral runs (fit --data A B [C]: leave-one-run-out, not scaled) → another FE run")
    for size in sorted({len(r["model_runs"]) for r in rows}):
        part = [r for r in rows if len(r["model_runs"]) == size]
        ratio = np.array([r["actual_um"] / r["expected_um"] for r in part])
        inside = np.mean([r["range_um"][0] <= r["actual_um"] <= r["range_um"][1] for r in part])
        within = np.mean((ratio >= 0.5) & (ratio <= 2))
        print(
            f"{size} runs, {len(part)} pairs: actual/expected median {np.median(ratio):.2f} "
            f"({ratio.min():.2f}-{ratio.max():.2f}), in [0.5, 2]: {100 * within:.0f} %, "
            f"inside the printed range: {100 * inside:.0f} %"
        )
    ratio = [r["actual_um"] / r["expected_um"] for r in rows]
    low, high = np.percentile(ratio, calibration.LEVELS)
    print(f"10th-90th percentiles of actual / expected over all {len(rows)}: {low:.3g}-{high:.3g} (what ships)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a small subset")
    parser.add_argument("--json", metavar="FILE", help="write every pair's row as JSON")
    args = parser.parse_args()
    pairs = panel.simulator_pairs(range(3), range(0)) + panel.fe_pairs()[:2] if args.quick else panel.panel_pairs()
    rows = [panel.score_pair(pair) for pair in pairs]
    table(rows, f"calibration panel ({len(rows)} pairs), with the shipped calibration")
    measured_pairs = [] if args.quick else panel.measured_pairs()
    measured = [panel.score_pair(pair) for pair in measured_pairs]
    all_pairs = pairs + measured_pairs
    if measured:
        table(measured, "the shared measured test cut into runs")
    else:
        print("\nthe shared measured test is absent (../shared) or --quick: the panel alone calibrates")
    both = rows + measured
    raw = [r["raw_um"] for r in both]
    actual = [r["actual_um"] for r in both]
    derived = calibration.derive_calibration(raw[0::2], actual[0::2])
    print(f"\nderived on the even-numbered of all {len(both)} pairs: {derived}")
    summary(both[1::2], derived["factor"], "checked on the odd-numbered pairs")
    summary(both[0::2], derived["factor"], "on the even-numbered pairs themselves")
    print(f"derived on all {len(both)} pairs (what ships): {calibration.derive_calibration(raw, actual)}")
    summary(both, calibration.FACTOR, f"all {len(both)} pairs with the shipped factor")
    within_span(both, calibration.FACTOR)
    print(ceiling(both))
    blind = [] if args.quick else [panel.score_pair(panel.without_operating_columns(p)) for p in all_pairs]
    if blind:
        table(blind, "the same pairs logged without their operating columns (the estimate on blocks of time)")
    several = [] if args.quick else panel.several_run_rows()
    if several:
        several_summary(several)
    if args.json:
        Path(args.json).write_text(
            json.dumps(
                {"panel": rows, "measured": measured, "without_operating_columns": blind, "several_runs": several},
                indent=1,
                default=str,
            )
        )


if __name__ == "__main__":
    main()
