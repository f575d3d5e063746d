"""The closed loop on the measured spindle test: each speed block (with its cool-down) held out in turn.

Reads ``../shared/data/fl_thermal/spindle_step_test.csv`` (the first 60 % of a
measured 46 h step-speed test). For each held-out block the modelling runs are
the parts of the test before and after it; the base model is the MLR on the 16
sensors (``disp_ch3_um``), fitted on the modelling runs; ``groupfit diagnose``
chooses effects on the modelling runs only (leave-one-condition-out) and is
judged on the held-out block, through the run-time rule. A second table starts
from a model whose inputs were re-selected (``--select forward``), a third
from the 16-sensor model refitted with a ridge penalty chosen on the same
held-out conditions (``--ridge auto``). "RMS µm" is the model each diagnosis
started from.

    python bench/bench_diagnose_measured.py [--figure-dir DIR]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.select import ridge_base_model, select_base_model
from groupfit.modelfile import model_to_dict
from groupfit.models.grouped import GroupedRegressor
from groupfit.plots import plot_diagnosis
from groupfit.switching import replay_groups

MEASURED = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
SENSORS = [f"t{k}_C" for k in range(1, 17)]
BLOCKS = {
    "1250 r/min + cool-down": (31, 1951),
    "2500 r/min + cool-down": (1951, 3871),
    "3750 r/min + cool-down": (3871, 5791),
    "5000 r/min (last 3.7 h)": (5791, None),
}


def runs_around(frame, first, last):
    parts = [frame.iloc[:first], frame.iloc[last:] if last is not None else frame.iloc[:0]]
    runs = [
        load_run(p.reset_index(drop=True), temps=SENSORS, error="disp_ch3_um", name=f"part{k}")
        for k, p in enumerate(parts)
        if len(p) > 100
    ]
    held = frame.iloc[first:last].reset_index(drop=True)
    return runs, load_run(held, temps=SENSORS, error="disp_ch3_um", name="held_out")


def base_model(runs):
    X = np.vstack([r.temps for r in runs])
    y = np.concatenate([r.error for r in runs])
    joined = replace(runs[0], temps=X, error=y, time=np.arange(len(y)) * runs[0].period)
    return model_to_dict(GroupedRegressor(p=0).fit(X, y), joined)


def row(label, result):
    b, a = result.before["validate"]["rms_um"], result.after["validate"]["rms_um"]
    effects = "; ".join(f"{c.feature.column} {c.feature.describe()}" for c in result.added) or "nothing added"
    verdict = {True: "better", False: "WORSE", None: "unchanged"}[result.improved]
    return f"{label:<26} {b:>8.2f} {a:>8.2f} {100 * (a - b) / b:>+7.0f} %  {verdict:<9} {effects}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure-dir", default="bench-out", help="where the before/after figures go")
    args = parser.parse_args(argv)
    if not MEASURED.is_file():
        print(f"measured data not found at {MEASURED}; nothing to do", file=sys.stderr)
        return 0
    frame = pd.read_csv(MEASURED)
    out = Path(args.figure_dir)
    out.mkdir(parents=True, exist_ok=True)
    columns = f"{'held out':<26} {'RMS µm':>8} {'after':>8} {'change':>9}  {'verdict':<9}"
    header = columns + " effects added (chosen on the other blocks)"
    for start in ("16 sensors", "forward-selected", "16 sensors, ridge (auto)"):
        print(f"\nbase model: MLR on {start}")
        print(header)
        for label, (first, last) in BLOCKS.items():
            runs, held = runs_around(frame, first, last)
            model = base_model(runs)
            extra = ""
            if start == "forward-selected":
                model, info = select_base_model(model, runs, "forward")
                extra = f"  [inputs {','.join(info['inputs'])}]"
            elif start.endswith("ridge (auto)"):
                model, info = ridge_base_model(model, runs, "auto")
                extra = f"  [alpha {info['alpha']:g}]"
            result = diagnose(model, runs, held, live_rule=replay_groups)
            print(row(label, result) + extra)
            if start == "16 sensors":
                name = label.split()[0]
                plot_diagnosis(result, {"data": runs, "validate": [held]}, out / f"diagnose_measured_{name}.png")
    print(f"\nfigures in {out}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
