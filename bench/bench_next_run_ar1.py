"""The AR(1) model's next-run estimate on the pairs of the calibration panel that have a heat column.

Run from the repository root: ``python bench/bench_next_run_ar1.py`` (about 10 s).
For every pair of ``next_run_panel.py`` (model run → next run) whose model run
has an operating column to serve as the AR(1) model's heat input (a speed,
else the on/off of a source; the air's temperature never), the AR(1) model is
fitted as ``groupfit fit --model ar1 --heat COLUMN`` fits it by default (one-step
least squares, the free run from 0, the heat law's exponent 5/3). The raw figure
is :func:`groupfit.ar1.nextrun.ar1_forward_chaining` on the model run; the
actual is the routine (:class:`groupfit.ar1.rule.AR1Rule`) replayed over the
next run from 0, as ``groupfit replay`` replays an AR(1) model file (afresh,
also where the next run is the rest of the model run's recording). The
calibration is the grouped models' (:mod:`groupfit.heldout.calibration`),
learned without these rows: the bench checks that it holds for the AR(1) model.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import next_run_panel as panel  # noqa: E402
from bench_next_run import ceiling  # noqa: E402

from groupfit.ar1.fitting import fit_ar1_file  # noqa: E402
from groupfit.ar1.nextrun import expect_ar1, file_predictor  # noqa: E402
from groupfit.ar1.rule import AR1Rule  # noqa: E402
from groupfit.columns import usable_columns  # noqa: E402
from groupfit.errors import InputError  # noqa: E402
from groupfit.heldout import calibration  # noqa: E402
from groupfit.heldout.folds import operating_columns  # noqa: E402


def heat_column(run) -> str | None:
    """The operating column an AR(1) model of ``run`` takes as its heat: a speed, else another setting."""
    columns, _ = usable_columns(run.frame, {run.time_name, run.error_name, *run.temp_names})
    settings = [c for c in operating_columns(run.frame, columns) if "amb" not in c.lower()]
    speeds = [c for c in settings if "rpm" in c.lower() or "speed" in c.lower()]
    return (speeds or settings or [None])[0]


def score_pair(pair: panel.Pair) -> dict | str:
    """The AR(1) model's expected and actual next-run RMS on ``pair``, or why it has none."""
    heat = heat_column(pair.model)
    if heat is None or heat not in pair.next.frame:
        return "no heat column"
    q, e = pair.model.frame[heat].to_numpy(float), pair.model.error
    options = {"period_s": pair.model.period, "heat_name": heat, "error_name": "error", "source": pair.name}
    try:
        model = fit_ar1_file(q, e, **options).model
    except InputError as exc:
        return f"not fitted: {exc}"
    expectation = expect_ar1(
        q, e, file_predictor(q, e, lambda a, b: fit_ar1_file(a, b, **options).model), heat_name=heat
    )
    if expectation is None:
        return "no segment scored"
    prediction = AR1Rule(model).replay(pair.next.frame[heat].to_numpy(float)).prediction_um
    actual = float(np.sqrt(np.nanmean((pair.next.error - prediction) ** 2)))
    expected, (low, high) = expectation.expected()
    raw = float(expectation.scores.raw_rms()[0])
    return {
        "name": pair.name,
        "source": pair.source,
        "heat": heat,
        "raw_um": raw,
        "expected_um": expected,
        "range_um": (low, high),
        "actual_um": actual,
    }


def summary(rows: list[dict], label: str) -> None:
    if not rows:
        return
    ratio = np.array([r["actual_um"] / r["expected_um"] for r in rows])
    inside = np.mean([r["range_um"][0] <= r["actual_um"] <= r["range_um"][1] for r in rows])
    raw_ratio = np.array([r["actual_um"] / r["raw_um"] for r in rows])
    print(
        f"{label}: {len(rows)} pairs, actual/expected median {np.median(ratio):.2f}, in [0.5, 2]: "
        f"{100 * np.mean((ratio >= 0.5) & (ratio <= 2)):.0f} %, inside the printed range: {100 * inside:.0f} %; "
        f"median actual/raw {np.median(raw_ratio):.2f} (the shipped factor {calibration.FACTOR:g}); {ceiling(rows)}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args()
    rows = []
    print(f"{'pair':42s} {'source':9s} {'heat':12s} {'raw':>7s} {'expect':>7s} {'actual':>7s} {'ratio':>6s}")
    for pair in panel.panel_pairs() + panel.measured_pairs():
        row = score_pair(pair)
        if isinstance(row, str):
            print(f"{pair.name:42s} {pair.source:9s} {row}")
            continue
        rows.append(row)
        print(
            f"{row['name']:42s} {row['source']:9s} {row['heat']:12s} {row['raw_um']:7.3g} {row['expected_um']:7.3g} "
            f"{row['actual_um']:7.3g} {row['actual_um'] / row['expected_um']:6.2f}"
        )
    summary([r for r in rows if r["source"] != "measured"], "panel")
    summary([r for r in rows if r["source"] == "measured"], "shared measured test cut into runs")
    summary(rows, "all")


if __name__ == "__main__":
    main()
