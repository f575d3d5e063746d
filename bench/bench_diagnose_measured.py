"""The closed loop on the measured spindle test: each speed block (with its cool-down) held out in turn.

Reads ``../shared/data/fl_thermal/spindle_step_test.csv`` (the first 60 % of a
measured 46 h step-speed test). For each held-out block the modelling run is
the whole test with the block's error left empty, the validation run the
whole test with every other row's error left empty (a low-pass of the speed
keeps its history through the block, as on the controller); the base model is
the MLR on the 16 sensors (``disp_ch3_um``) fitted on the modelling rows;
``groupfit diagnose`` chooses effects on the modelling rows only
(leave-one-condition-out) and is judged on the held-out block, through the
run-time rule. The second, third and fourth tables start from a model
whose inputs were re-selected (``--select forward``, ``lasso``, ``cluster``),
the fifth from the 16-sensor model refitted with a ridge penalty chosen on
the same held-out conditions (``--ridge auto``), the sixth from the 16-sensor
model whose inputs are chosen together with the effects (``--select joint``;
its nested held-out forecast is shown next to the given model's held-out
RMS). "RMS µm" is the model each diagnosis started from (the 16-sensor model
for the sixth). Three more tables follow.

* The log cut: the test cut in two files at 50 … 90 %, validated on the
  second, once as the continuation of the first (its derived inputs carry
  the first file's history, as on the controller), once after an hour's gap
  (the controller restarted: from rest), and once cut in two halves, two
  files that continue each other, each judged on its own.
* Was a −40 % on a held-out block within reach? For each τ of the speed's
  heat-law low-pass, the score the diagnosis gave it on the other blocks,
  how many of their folds it improved and why it was not taken (the drift
  guard left aside), next to the held-out RMS of the 16-sensor model with
  that one input added, fitted on the other blocks.
* Would another rule have chosen better? Each rule picks one heat-law
  low-pass of the speed from the scores on the other blocks (the drift guard
  left aside), and the table gives its pick on each held-out block, with
  that block's RMS, and on the whole file. The rules: the diagnosis's own
  (the shortest lag within one standard error of the best that passes every
  test), the best score, the longest lag within one standard error, each of
  these with the majority test dropped, the heat law's exponent k chosen
  too (k = 1 … 3), and folds that are whole speed blocks with their
  cool-downs (least squares on the 16 sensors and the lag, the same tests).

    python bench/bench_diagnose_measured.py [--figure-dir DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.data import load_run, measured_rows
from groupfit.diagnose import diagnose
from groupfit.diagnose.candidates import TAUS_S, heat_law_scale, score_candidate, within_one_se
from groupfit.diagnose.effects import shortest_adequate_lag
from groupfit.diagnose.loop import MIN_EFFECT_RMS_UM, MIN_SCORE
from groupfit.diagnose.plot import plot_diagnosis
from groupfit.diagnose.policy import DEFAULT_POLICY, FEW_FOLDS
from groupfit.diagnose.select import ridge_base_model, select_base_model
from groupfit.features import Feature
from groupfit.heldout.folds import Folds
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.models.grouped import GroupedRegressor
from groupfit.runtime import replay_groups

MEASURED = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
SENSORS = [f"t{k}_C" for k in range(1, 17)]
BLOCKS_START = 31
"""The first row of the first block (the spindle starts at 1250 r/min); the rows before it are at rest."""
BLOCKS = {
    "1250 r/min + cool-down": (BLOCKS_START, 1951),
    "2500 r/min + cool-down": (1951, 3871),
    "3750 r/min + cool-down": (3871, 5791),
    "5000 r/min (last 3.7 h)": (5791, None),
}


def runs_around(frame, first, last):
    """The test with the block's error left empty (modelling), and with every other row's (validation).

    Both keep every row: the controller runs through the whole test, so a
    low-pass of the spindle speed carries its history into and out of the
    held-out block; only the rows with an error count, in the fit and in the
    score.
    """
    block = np.zeros(len(frame), dtype=bool)
    block[first:last] = True
    modelling, held = frame.copy(), frame.copy()
    modelling.loc[block, "disp_ch3_um"] = np.nan
    held.loc[~block, "disp_ch3_um"] = np.nan
    runs = [load_run(modelling, temps=SENSORS, error="disp_ch3_um", name="others", allow_nonfinite=True)]
    return runs, load_run(held, temps=SENSORS, error="disp_ch3_um", name="held_out", allow_nonfinite=True)


def base_model(runs):
    """The MLR on the 16 sensors, fitted on the rows with a measured error."""
    fitted = measured_rows(runs[0])
    return GroupedRegressor(p=0).fit(fitted.temps, fitted.error).to_model_file(fitted).to_dict()


FORWARD_CUTS = (0.5, 0.6, 0.7, 0.8, 0.9)


def forward_split_row(frame, cut):
    """Diagnose with the rows after ``cut`` as a second file: continuing the first, and after an hour's gap;
    then with them as two files, each continuing the one before, judged each on its own."""
    modelling = load_run(frame.iloc[:cut].reset_index(drop=True), temps=SENSORS, error="disp_ch3_um", name="first")
    model = base_model([modelling])
    cells = []
    for gap_s in (0.0, 3600.0):
        later = frame.iloc[cut:].reset_index(drop=True)
        later["time_s"] += gap_s
        validation = load_run(later, temps=SENSORS, error="disp_ch3_um", name="second")
        result = diagnose(model, [modelling], [validation], live_rule=replay_groups)
        b, a = result.before["validate"]["rms_um"], result.after["validate"]["rms_um"]
        cells.append(f"{b:.2f} → {a:.2f} µm ({100 * (a - b) / b:+.0f} %)")
    effects = "; ".join(c.feature.describe() for c in result.added) or "nothing added"
    middle = (cut + len(frame)) // 2
    halves = [
        load_run(frame.iloc[rows].reset_index(drop=True), temps=SENSORS, error="disp_ch3_um", name=name)
        for name, rows in (("second", slice(cut, middle)), ("third", slice(middle, None)))
    ]
    in_two = diagnose(model, [modelling], halves, live_rule=replay_groups)
    each = ", ".join(f"{r.before['rms_um']:.2f} → {r.after['rms_um']:.2f}" for r in in_two.validation_runs) + (
        " (worse on one)" if in_two.worse_runs else ""
    )
    return f"{cut / len(frame):<10.0%} {cells[0]:>32} {cells[1]:>32} {each:>42}  {effects}"


def tau_sweep(frame, label, first, last):
    """Each τ of the heat-law low-pass: its score on the other blocks, its fate, and its held-out RMS."""
    runs, held = runs_around(frame, first, last)
    result = diagnose(base_model(runs), runs, held, live_rule=replay_groups)
    chosen = {c.feature for c in result.added}
    first_score = min((c.score for c in result.added), default=np.inf)
    lines = [f"{label}: RMS {result.before['validate']['rms_um']:.2f} µm without an effect"]
    for candidate in result.candidates:
        feature = candidate.feature
        if feature.column != "spindle_rpm" or feature.transform != "lowpass":
            continue
        held_out = held_out_rms(frame, first, last, feature)
        if feature in chosen:
            fate = "added"
        elif candidate.score < MIN_SCORE:
            fate = "below the least score"
        elif refusal := fold_refusal(candidate):
            fate = refusal.reason
        elif candidate.score > first_score:
            fate = "passes; a shorter lag within one standard error was taken"
        else:
            fate = "passes, scored lower"
        folds = f"{candidate.n_folds_improved}/{len(candidate.fold_ratios)}"
        lines.append(
            f"  τ = {feature.tau_s / 3600:>4.2g} h  score {candidate.score:+.2f}  folds better {folds}  "
            f"held-out {held_out:6.2f} µm  {fate}"
        )
    return lines


RULE_EXPONENTS = (1.0, 4.0 / 3.0, 5.0 / 3.0, 2.0, 2.5, 3.0)
"""Heat-law exponents the rule that chooses k too picks from."""


def fold_refusal(candidate):
    """The tests on the held-out folds a first effect faces, without its drift guard."""
    return DEFAULT_POLICY.fold_refusal(candidate, further=False, own_transforms=False)


def heat_lags(runs, exponent):
    """The diagnosis's candidates that are heat-law low-passes of the speed with ``exponent``, best first."""
    result = diagnose(base_model(runs), runs, live_rule=replay_groups, heat_exponent=exponent, max_effects=1)
    return [
        c
        for c in result.candidates
        if c.feature.column == "spindle_rpm" and c.feature.transform == "lowpass" and c.feature.exponent
    ]


def block_folds_lags(frame, held_out, exponent=5.0 / 3.0):
    """Heat-law low-passes scored by the diagnosis's scorer on folds that are whole speed blocks with their
    cool-downs (the other blocks than ``held_out``; all four when it is None): the 16 sensors' regression."""
    labels = np.full(len(frame), -1)  # never held out: always fitted
    modelling = np.ones(len(frame), dtype=bool)
    for k, (label, (first, last)) in enumerate(BLOCKS.items()):
        if label == held_out:
            modelling[first:last] = False
        else:  # the rows at rest before the first block are held out with it, as the diagnosis's folds do
            labels[0 if first == BLOCKS_START else first : last] = k
    folds = Folds(labels[modelling], "block", scored=labels[modelling] >= 0)
    design = np.column_stack([np.ones(len(frame)), frame[SENSORS].to_numpy(float)])[modelling]
    scorer = HeldOutScorer(frame["disp_ch3_um"].to_numpy(float)[modelling], design, folds)
    scale = heat_law_scale(frame["spindle_rpm"].to_numpy(float))
    candidates = []
    for tau in TAUS_S:
        feature = Feature("spindle_rpm", "lowpass", tau_s=tau, start="rest", exponent=exponent, scale=scale)
        candidates.append(score_candidate(feature, speed_feature(frame, feature)[modelling], scorer))
    return sorted(candidates, key=lambda c: -c.score)


def speed_feature(frame, feature):
    """``feature`` of the spindle speed over the whole test, at the test's sampling period."""
    period = float(np.median(np.diff(frame["time_s"].to_numpy(float))))
    return feature.compute(frame["spindle_rpm"].to_numpy(float), period)


def measured_run(frame):
    return load_run(frame, temps=SENSORS, error="disp_ch3_um", name="spindle_step_test")


def pick(candidates, prefer, majority=True):
    """The low-pass a rule takes: the best-scoring one that passes, or the shortest / longest within one standard
    error of it (``prefer``: "best", "shortest", "longest"); ``majority=False`` drops the majority test."""

    def passes(c):
        if c.score < MIN_SCORE or c.explained_rms_um < MIN_EFFECT_RMS_UM:
            return False
        refusal = fold_refusal(c)
        return refusal is None or (not majority and refusal.rule_id == FEW_FOLDS)

    passing = [c for c in candidates if passes(c)]
    if not passing:
        return None
    best = max(passing, key=lambda c: c.score)
    family = [c for c in passing if c.family() == best.family()]
    if prefer == "best":
        return best
    if prefer == "shortest":
        return shortest_adequate_lag(best, family, DEFAULT_POLICY)
    return max([best, *(c for c in family if within_one_se(c, best))], key=lambda c: c.feature.tau_s)


def held_out_rms(frame, first, last, feature):
    """The 16-sensor model with ``feature`` (none: without), fitted on the other blocks, on the held-out one."""
    block = np.zeros(len(frame), dtype=bool)
    block[first:last] = True
    columns = [frame[SENSORS].to_numpy(float), np.ones(len(frame))]
    if feature is not None:
        columns.append(speed_feature(frame, feature))
    design, error = np.column_stack(columns), frame["disp_ch3_um"].to_numpy(float)
    coefficients, *_ = np.linalg.lstsq(design[~block], error[~block], rcond=None)
    return float(np.sqrt(np.mean((error[block] - design[block] @ coefficients) ** 2)))


def lag_words(feature):
    if feature is None:
        return "nothing"
    k = "" if abs(feature.exponent - 5.0 / 3.0) < 1e-9 else f" k={feature.exponent:.3g}"
    tau = f"{feature.tau_s / 60:g} min" if feature.tau_s < 3600 else f"{feature.tau_s / 3600:g} h"
    return tau + k


def rule_variants(frame):
    """Each rule's pick on each held-out block (with the block's RMS) and on the whole file."""
    rules = {
        "diagnose: shortest within 1 SE": ("diagnosis", "shortest", True),
        "best score": ("diagnosis", "best", True),
        "longest within 1 SE": ("diagnosis", "longest", True),
        "shortest within 1 SE, no majority test": ("diagnosis", "shortest", False),
        "best score, no majority test": ("diagnosis", "best", False),
        "longest within 1 SE, no majority test": ("diagnosis", "longest", False),
        "best score, k chosen too": ("exponents", "best", True),
        "blocks with cool-down, best score": ("blocks", "best", True),
        "blocks with cool-down, shortest within 1 SE": ("blocks", "shortest", True),
    }
    setups = {label: runs_around(frame, first, last)[0] for label, (first, last) in BLOCKS.items()}
    setups["whole file"] = [measured_run(frame)]
    scored = {}
    for label, runs in setups.items():
        held_out = None if label == "whole file" else label
        by_k = [c for k in RULE_EXPONENTS for c in heat_lags(runs, k)]
        scored[label] = {
            "diagnosis": [c for c in by_k if abs(c.feature.exponent - 5.0 / 3.0) < 1e-9],
            "exponents": by_k,
            "blocks": block_folds_lags(frame, held_out),
        }
    bases = {label: held_out_rms(frame, first, last, None) for label, (first, last) in BLOCKS.items()}
    lines = [
        f"{'rule':<44}" + "".join(f"{label.split()[0]:>27}" for label in BLOCKS) + f"{'blocks -40 %':>14}  whole file"
    ]
    lines.append(f"{'no effect (RMS µm)':<44}" + "".join(f"{bases[label]:>27.2f}" for label in BLOCKS))
    for name, (source, prefer, majority) in rules.items():
        cells, reached = [], 0
        for label, (first, last) in BLOCKS.items():
            chosen = pick(scored[label][source], prefer, majority)
            feature = None if chosen is None else chosen.feature
            rms = held_out_rms(frame, first, last, feature)
            reached += rms <= 0.6 * bases[label]
            cells.append(f"{lag_words(feature)} {rms:.2f} ({100 * (rms / bases[label] - 1):+.0f} %)")
        whole = pick(scored["whole file"][source], prefer, majority)
        lines.append(
            f"{name:<44}"
            + "".join(f"{cell:>27}" for cell in cells)
            + f"{f'{reached} of {len(BLOCKS)}':>14}  {lag_words(None if whole is None else whole.feature)}"
        )
    return lines


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
    starts = ("16 sensors", "forward-selected", "lasso-selected", "cluster-selected", "16 sensors, ridge (auto)")
    for start in (*starts, "16 sensors, joint selection"):
        print(f"\nbase model: MLR on {start}")
        print(header)
        for label, (first, last) in BLOCKS.items():
            runs, held = runs_around(frame, first, last)
            model = base_model(runs)
            extra = ""
            if start.endswith("-selected"):
                model, info = select_base_model(model, runs, start.split("-")[0])
                extra = f"  [inputs {','.join(info.inputs)}]"
            elif start.endswith("ridge (auto)"):
                model, info = ridge_base_model(model, runs, "auto")
                extra = f"  [alpha {info.alpha:g}]"
            joint = start.endswith("joint selection")
            result = diagnose(model, runs, held, live_rule=replay_groups, select_jointly=joint)
            if joint:
                selection = result.selection
                extra = (
                    f"  [inputs {','.join(selection.inputs)}; nested held-out "
                    f"{selection.nested_held_out_rms_um:.2f} vs {result.base_check.held_out_rms_um:.2f} µm]"
                )
            print(row(label, result) + extra)
            suffix = {"16 sensors": "", "16 sensors, ridge (auto)": "_ridge", "16 sensors, joint selection": "_joint"}
            suffix = suffix.get(start, "_" + start.split("-")[0])
            name = f"diagnose_measured_{label.split()[0]}{suffix}.png"
            plot_diagnosis(result, {"data": runs, "validate": [held]}, out / name)
    print("\nthe log cut in two files: modelling up to the cut, validation after it (16-sensor start)")
    print(
        f"{'cut':<10} {'continuing the modelling file':>32} {'after an hour gap (from rest)':>32} "
        f"{'as two files, each half µm':>42}  effects added"
    )
    for share in FORWARD_CUTS:
        print(forward_split_row(frame, int(share * len(frame))))
    print("\nwas a 40 % cut within reach? the heat-law low-pass at each τ (16-sensor start)")
    for label, (first, last) in BLOCKS.items():
        print("\n".join(tau_sweep(frame, label, first, last)))
    print(
        "\nwould another rule have chosen better? the heat-law low-pass each rule takes from the other blocks' "
        "scores: τ, the held-out block's RMS µm (16-sensor start; the drift guard left aside)"
    )
    print("\n".join(rule_variants(frame)))
    print(f"\nfigures in {out}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
