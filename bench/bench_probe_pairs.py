"""Probe checks on the next run, pair by pair: how much of the unchecked error a check every T leaves.

Usage::

    python bench/bench_probe_pairs.py [--json FILE] [--every 30m,60m] [--diagnose] [--only NAME ...]
                                      [--fit-args='--p 1']

Every pair is a model run and a later run of the same machine the model never
saw, the calibration panel of the next-run estimate (``bench/next_run_panel.py``:
the independent simulator's random machines and days, the finite-element
repeats and other-condition runs, the diagnosis data sets' model → validate
pairs) and, reported apart, cuts of the shared measured test. Each model is
built as a user builds it, ``groupfit fit`` with its defaults (``--diagnose``:
then ``groupfit diagnose`` on the model run), on the whole model run; the next
run is replayed with ``groupfit replay`` (the model file's run-time rule and
recalibration section; a next run whose clock continues the model run is
replayed after it, as ``replay`` does unasked), without checks and with a
check every T: the first one interval into the run (``replay --probe-every
T``, the default) and at the run's first sample (``--probe-first 0``).

Printed per pair: RMS without checks and with them, and the ratio; overall,
the share of pairs where the checks leave at most half the unchecked RMS,
per schedule and interval; how many pairs the checks leave worse than
without them (by more than 5 %), and whether the model run's held-out
stretches (``recalibration.chosen``) said so beforehand; and the share halved among the pairs whose
model is off on the next run (its unchecked RMS more than twice the model
run's in-sample RMS), not at its noise floor. The probe reading is the run's
measured error.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_recalibration import quiet_main  # noqa: E402
from next_run_panel import (  # noqa: E402
    DATASETS,
    DIAG_KINDS,
    FE_PAIRS,
    MEASURED,
    MEASURED_SENSORS,
    measured_cuts,
    simulator_scenarios,
)

from groupfit.model import ModelFile  # noqa: E402
from groupfit.probe_intervals import parse_intervals  # noqa: E402

SCHEDULES = {"after T": None, "at start": 0}
WORSE_TOLERANCE = 1.05
"""The issue's "never worse than no checks", counted with 5 % to spare (a check's own noise)."""
OFF_FACTOR = 2.0
"""A next run whose unchecked RMS exceeds this many times the model run's in-sample RMS finds the model off."""


def pair_frames():
    """(name, source, model frame, next frame, temps, error column) of every pair."""
    for name, scenario in simulator_scenarios():
        yield name, "simulator", scenario.modelling, scenario.validation, list(scenario.temps), "error_um"
    for a, b in FE_PAIRS:
        frames = [pd.read_csv(DATASETS / f"{x}.csv") for x in (a, b)]
        yield f"{a}→{b}", "FE", *frames, ["T1", "T2"], "error_um"
    for kind in DIAG_KINDS:
        frames = [pd.read_csv(DATASETS / f"diag_{kind}_{x}.csv") for x in ("model", "validate")]
        yield f"diag_{kind}", "FE diag", *frames, ["T1", "T2"], "error_um"
    if MEASURED.exists():
        whole = pd.read_csv(MEASURED)
        for name, model, following, _ in measured_cuts(len(whole)):
            yield name, "measured", whole.iloc[model], whole.iloc[following], MEASURED_SENSORS, "disp_ch3_um"


@dataclass(frozen=True)
class BuiltPair:
    """A pair on disk: the model built on its model run (``folder/model_run.csv``) and its next run."""

    name: str
    source: str
    folder: Path
    model_path: Path
    next_path: Path
    temps: list
    error: str


def built_pairs(root: Path, *, only=None, diagnose: bool = False, fit_args=()):
    """Every pair (or those named in ``only``) with its model built under ``root``, one folder each."""
    for k, (name, source, model, following, temps, error) in enumerate(pair_frames()):
        if only and name not in only:
            continue
        folder = root / f"pair{k}"
        folder.mkdir()
        model_path = build(folder, model, temps, error, diagnose=diagnose, fit_args=fit_args)
        next_path = folder / "next_run.csv"
        following.to_csv(next_path, index=False)
        yield BuiltPair(name, source, folder, model_path, next_path, list(temps), error)


def build(folder: Path, frame: pd.DataFrame, temps, error: str, *, diagnose: bool, fit_args=()) -> Path:
    """``groupfit fit`` with its defaults (and ``diagnose``) on the model run; the model file left. ``fit_args``:
    options added to ``fit`` (``--fit-args``)."""
    modelling = folder / "model_run.csv"
    frame.to_csv(modelling, index=False)
    log = folder / "groupfit.log"
    args = ["fit", "--data", str(modelling), "--error", error, "--temps", ",".join(temps), "--out", str(folder / "fit")]
    quiet_main(args + ["--quiet", "--no-budget", *fit_args], log)
    model = folder / "fit" / "model.json"
    if diagnose:
        quiet_main(["diagnose", str(model), "--data", str(modelling), "--out", str(folder / "diag")], log)
        augmented = folder / "diag" / "model_augmented.json"
        model = augmented if augmented.exists() else model
    return model


def replayed(folder: Path, model_path: Path, following: Path, *args: str) -> dict:
    """``groupfit replay`` as a user runs it (a file that continues the model run is replayed after it)."""
    out = folder / "replay.json"
    quiet_main(["replay", str(model_path), "--data", str(following), *args, "--json", str(out)], folder / "replay.log")
    return json.loads(out.read_text())


def pair_result(name, source, model_path: Path, following: Path, intervals_s) -> dict:
    folder = model_path.parent
    model = ModelFile.load(model_path)
    none = replayed(folder, model_path, following)
    checked = {}
    for label, first in SCHEDULES.items():
        extra = () if first is None else ("--probe-first", f"{first:g}")
        checked[label] = [
            replayed(folder, model_path, following, "--probe-every", f"{t:g}", *extra)["rms_um"] for t in intervals_s
        ]
    return {
        "pair": name,
        "source": source,
        "p": model.p,
        "recalibration": model.recalibration.description if model.recalibration else "none",
        "chosen": dict(model.recalibration.chosen or {}) if model.recalibration else {},
        "continued": bool(none["continues"]),
        "rms_none_um": none["rms_um"],
        "rms_in_sample_um": float(model.training["rms_um"]),
        "clamped": none.get("clamped_samples"),
        "rms_um": checked,
        "held_out_worse": [held_out_worse(model, t) for t in intervals_s],
    }


def report(results: list[dict], intervals_s) -> str:
    heads = [f"{t / 60:g} min" for t in intervals_s]
    columns = "".join(f"{s + ' ' + h:>22}" for s in SCHEDULES for h in heads)
    lines = [f"{'pair':<56}{'source':<11}{'p':>2}{'none µm':>10}{columns}"]
    for r in results:
        none = r["rms_none_um"]
        cells = "".join(f"{f'{v:.3g} ({v / none:.2f})':>22}" for s in SCHEDULES for v in r["rms_um"][s])
        name = r["pair"] + (" (continued)" if r["continued"] else "")
        lines.append(f"{name:<56}{r['source']:<11}{r['p']:>2}{r['rms_none_um']:>10.3g}{cells}")
    for group, members in (
        ("panel", [r for r in results if r["source"] != "measured"]),
        ("measured", [r for r in results if r["source"] == "measured"]),
    ):
        if not members:
            continue
        for s in SCHEDULES:
            shares = []
            for k, h in enumerate(heads):
                median = float(np.median([r["rms_um"][s][k] / r["rms_none_um"] for r in members]))
                shares.append(f"{h}: {halved(members, s, k)}/{len(members)} at most half (median ratio {median:.2f})")
            lines.append(f"{group:<9} first check {s:<9} " + "; ".join(shares))
    lines += [worse_than_none(results, heads), off_the_floor(results, heads), held_out_foretold(results, heads)]
    return "\n".join(lines)


def halved(results: list[dict], schedule: str, k: int) -> int:
    """How many pairs the checks of ``schedule`` at the ``k``-th interval leave at most half the unchecked RMS."""
    return sum(r["rms_um"][schedule][k] <= 0.5 * r["rms_none_um"] for r in results)


def worse_than_none(results: list[dict], heads) -> str:
    """How many pairs the checks leave worse than no checks by more than 5 %, per schedule and interval."""
    cells = []
    for s in SCHEDULES:
        for k, h in enumerate(heads):
            worse = [r for r in results if r["rms_um"][s][k] > WORSE_TOLERANCE * r["rms_none_um"]]
            worst = max((r["rms_um"][s][k] / r["rms_none_um"] for r in worse), default=1.0)
            cells.append(f"{s} {h}: {len(worse)}/{len(results)} (worst ×{worst:.2f})")
    return f"worse than no checks by more than {100 * (WORSE_TOLERANCE - 1):.0f} %: " + "; ".join(cells)


def held_out_worse(model: ModelFile, interval_s: float) -> bool | None:
    """Whether the chosen filter did worse than no checks (by more than 5 %) at ``interval_s`` on the model
    run's held-out stretches (``recalibration.chosen``); None when the tuning did not try that interval."""
    chosen = model.recalibration.chosen if model.recalibration else None
    if not chosen or interval_s not in chosen.get("intervals_s", ()) or "rms_none_by_interval_um" not in chosen:
        return None
    k = list(chosen["intervals_s"]).index(interval_s)
    return chosen["rms_chosen_um"][k] > WORSE_TOLERANCE * chosen["rms_none_by_interval_um"][k]


def held_out_foretold(results: list[dict], heads) -> str:
    """Whether the model run's held-out stretches foretold the next runs the checks made worse than none."""
    cells = []
    for k, h in enumerate(heads):
        worse = [r["rms_um"]["after T"][k] > WORSE_TOLERANCE * r["rms_none_um"] for r in results]
        said = [bool(r["held_out_worse"][k]) for r in results]
        both = sum(w and v for w, v in zip(worse, said))
        cells.append(f"{h}: said {sum(said)}, of them worse {both}; worse {sum(worse)}, of them said {both}")
    return "held-out stretches that said checks do worse than none, against the next run: " + "; ".join(cells)


def off_the_floor(results: list[dict], heads) -> str:
    """The share halved among the pairs whose model is off on the next run, not at its noise floor.

    Off: the next run's unchecked RMS exceeds :data:`OFF_FACTOR` times the model run's in-sample RMS. A
    model at its floor leaves checks nothing to correct (their own noise is of the same size).
    """
    off = [r for r in results if r["rms_none_um"] > OFF_FACTOR * r["rms_in_sample_um"]]
    cells = []
    for s in SCHEDULES:
        for k, h in enumerate(heads):
            cells.append(f"{s} {h}: {halved(off, s, k)}/{len(off)}")
    return (
        f"at most half, where the next run's unchecked RMS exceeds {OFF_FACTOR:g}× the model run's in-sample RMS "
        f"({len(off)} of {len(results)} pairs): " + "; ".join(cells)
    )


def run(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results here")
    parser.add_argument("--every", default="30m,60m", help="check intervals (default 30m,60m)")
    parser.add_argument("--diagnose", action="store_true", help="run groupfit diagnose on the model run too")
    parser.add_argument("--only", nargs="+", help="pair names")
    parser.add_argument(
        "--fit-args", default="", help="options added to every groupfit fit, in one string (e.g. --fit-args='--p 1')"
    )
    args = parser.parse_args(argv)
    intervals = parse_intervals(args.every)
    started = time.perf_counter()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for pair in built_pairs(Path(tmp), only=args.only, diagnose=args.diagnose, fit_args=args.fit_args.split()):
            results.append(pair_result(pair.name, pair.source, pair.model_path, pair.next_path, intervals))
            print(f"{pair.name}: none {results[-1]['rms_none_um']:.3g} µm, {results[-1]['rms_um']}", flush=True)
    print(report(results, intervals))
    print(f"{len(results)} pair(s) in {time.perf_counter() - started:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(run())
