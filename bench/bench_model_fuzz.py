"""Fuzz the model-file validator: thousands of mutated model files through loading, replay and export.

Not a test (``tests/test_model_validation.py`` holds the property tests and a
slow hypothesis run of 3000 mutations). Each mutation deletes one key or
replaces one value at any depth of a valid model file by a hostile value
(another type, NaN, ±inf, ±1e308, −1; −1 is not used on coefficients, where it
is a valid number) or shifts a structural whole number by one, and then:

* loads it (``ModelFile.from_dict``); a refusal must be an ``InputError`` of one line;
* when it loads, replays the modelling run with the run-time rule and renders
  every export target; the groups and predictions must be those of the
  original model.

It prints how many mutations were refused, accepted with identical
decisions, crashed (any other exception: a traceback on the command line),
and how many were exported although invalid (accepted but deciding
differently). The last two must be 0.

    python bench/bench_model_fuzz.py                 # 5000 mutations, about a minute
    python bench/bench_model_fuzz.py --count 500 --seed 1
    python bench/bench_model_fuzz.py --derived     # a model with derived inputs (low-pass, power stage, delay)
    python bench/bench_model_fuzz.py --position    # a model with position terms and a dead band
    python bench/bench_model_fuzz.py --screw       # the ball-screw model file (screw predict)
    python bench/bench_model_fuzz.py --recalibration  # the recalibration section, replayed with probe checks

For ``--position`` (``--recalibration``) the mutations are drawn among the
``position`` and ``dead_band`` sections (the ``recalibration`` section)
only (the rest is fuzzed by the default run); for ``--screw`` the
ball-screw model file is loaded as ``screw predict`` loads it and its
predicted temperature rises must be the original's.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.export import TARGETS, render
from groupfit.model import DeadBand, ModelFile
from groupfit.model_recalibration import OPTIONAL_DEFAULTS
from groupfit.models.grouped import GroupedRegressor
from groupfit.position import load_position_run, with_position
from groupfit.runtime import RuleTables, SwitchingRule
from groupfit.screw import BallScrewModel
from groupfit.screw.modelfile import checked_model, model_to_dict
from groupfit.screw.runs import load_screw_run

DATA = Path(__file__).resolve().parents[1] / "datasets" / "synthetic_cycle.csv"
SCREW_DATA = Path(__file__).resolve().parents[1] / "datasets" / "screw_A.csv"
DERIVED_DATA = Path(__file__).resolve().parents[1] / "datasets" / "diag_ambient_model.csv"
HOSTILE = [None, True, False, "text", [], {}, [1, 2], math.nan, math.inf, -math.inf, 1e308, -1e308, -1]
STRUCTURAL = {"p", "n", "n_samples", "breaks", "hard_groups", "soft_groups", "criterion_index", "windows"}
"""Whole numbers shifted by one (not those of derived inputs: a delay of 4 samples is another valid model)."""


FREE = (("switching", "source_ranges"), ("position", "coefficients"), ("position", "p0_mm"), ("position", "travel_mm"))
"""Where −1 or [1, 2] is a valid value (another model, not a corrupt one), besides the coefficients (and a
ball-screw source's C1 and C2, fitted constants of either sign)."""


def base_model():
    """A p = 3 model of the synthetic run, and the rule's readings of that run."""
    run = load_run(DATA, temps=["T1", "T2", "T3", "T4"])
    estimator = GroupedRegressor(p=3, n=3, search="exact").fit(run.temps, run.error)
    return estimator.to_model_file(run).to_dict(), run.temps


def derived_model():
    """A p = 2 model with derived inputs (low-pass, heat-law power stage, delay from rest), as diagnose adds them."""
    from groupfit.diagnose.augment import augment_model
    from groupfit.diagnose.residual import model_inputs
    from groupfit.features import Feature
    from groupfit.runtime import RuleTables

    run = load_run(DERIVED_DATA, temps=["T1", "T2", "T3", "T4"])
    estimator = GroupedRegressor(n=3, fixed_breaks=[344, 528]).fit(run.temps, run.error)
    model = estimator.to_model_file(run, "T1").to_dict()
    for feature in (
        Feature("T_amb", "lowpass", tau_s=1800.0),
        Feature("speed_rpm", exponent=5 / 3, scale=1000.0),
        Feature("T_amb", "delay", delay_samples=3, start="rest"),
    ):
        model = augment_model(model, run, model_inputs(model, run), feature).to_dict()
    names = RuleTables.from_model(model).raw_names
    return model, np.column_stack([run.frame[name].to_numpy(dtype=float) for name in names])


def position_model():
    """A p = 0 model with second-order position terms and a dead band, on check runs at three positions."""
    run = load_run(DATA, temps=["T1", "T2", "T3", "T4"])
    frame = run.frame.assign(T_amb=20.0 + 0.1 * np.sin(np.arange(run.n_samples) / 7.0))
    long = pd.concat(
        [frame.assign(P_mm=p, error_um=frame["error_um"] * (1 + 0.002 * p) + 0.01 * p) for p in (0.0, 150.0, 300.0)]
    ).sort_values("time_s", kind="stable")
    prun = load_position_run(long, "P_mm", temps=["T1", "T2", "T3", "T4"])
    estimator = GroupedRegressor(p=0).fit(prun.run.temps, prun.run.error)
    model = with_position(
        estimator.to_model_file(prun.run), prun, 2, 150.0, dead_band=DeadBand(reference="T_amb", threshold_c=0.5)
    )
    model = model.to_dict()
    names = RuleTables.from_model(model).raw_names
    return model, long[list(names)].to_numpy(dtype=float)


def recalibration_model():
    """The p = 3 model with a recalibration section, and its readings with a probe check every 20 samples."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from recalibration_cases import KALMAN  # a Kalman filter on offset, drift and gain: every number in play

    model, temps = base_model()
    run = load_run(DATA, temps=["T1", "T2", "T3", "T4"])
    probes = np.full(run.n_samples, np.nan)
    probes[::20] = run.error[::20] + 1.5  # the machine drifted 1.5 µm since the fit
    return {**model, "recalibration": dict(KALMAN)}, (temps, probes)


def recalibration_decisions(model, data):
    """Load as replay does, replay the rule with the probe checks and render every target."""
    temps, probes = data
    loaded = ModelFile.from_dict(model)
    replay = SwitchingRule(loaded).replay(temps, probes)
    for target in TARGETS:
        render(loaded, target)
    return replay.group, replay.compensation_um, replay.probe


def with_defaults(section: dict) -> dict:
    """The recalibration section with every optional key it leaves out written with its default."""
    return {**{k: list(v) if isinstance(v, tuple) else v for k, v in OPTIONAL_DEFAULTS.items()}, **section}


SWITCHING_DEFAULTS = {"blend_samples": 0}
"""Keys of the switching section a file may leave out, and what their absence means (files written before
the bumpless transfer have no ``blend_samples``: no transfer)."""


def without_optional_switching(model: dict, mutated: dict) -> dict | None:
    """The original model with the optional switching key ``mutated`` leaves out set to its default, or None
    when ``mutated`` does not leave one out."""
    section, original = mutated.get("switching"), model["switching"]
    if not isinstance(section, dict):
        return None
    dropped = [key for key in SWITCHING_DEFAULTS if key in original and key not in section]
    if not dropped:
        return None
    return {**model, "switching": {**original, **{key: SWITCHING_DEFAULTS[key] for key in dropped}}}


def same(result, reference) -> bool:
    return all(np.array_equal(a, b, equal_nan=True) for a, b in zip(result, reference))


def screw_model():
    """The ball-screw model identified on the shipped run A, and that run."""
    run = load_screw_run(SCREW_DATA)
    model = BallScrewModel().fit(run.rises, run.time, run.positions, source=run.name, label=run.source)
    return model_to_dict(model), run


def screw_decisions(data, run):
    """The rises ``screw predict`` computes with this model file (InputError when it is refused)."""
    model = checked_model(data, "model file")
    source = next(iter(model.sources_))
    return model.predict(run.time, run.positions, model.law_input(run.rises, run.positions, run.source), source)


def paths(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for key, item in value.items():
            yield from paths(item, (*prefix, key))
    elif isinstance(value, list):
        for k, item in enumerate(value[:6]):
            yield from paths(item, (*prefix, k))


def get(obj, path):
    for key in path:
        obj = obj[key]
    return obj


def mutate(model, all_paths, rng):
    path = all_paths[rng.integers(len(all_paths))]
    mutated = copy.deepcopy(model)
    current = get(model, path)
    container = get(mutated, path[:-1])
    structural = (
        isinstance(current, int)
        and not isinstance(current, bool)
        and path[0] != "derived_inputs"
        and any(p in STRUCTURAL for p in path)
    )
    kind = rng.choice(["replace", "delete", "shift"] if structural else ["replace", "delete"])
    if kind == "delete":
        del container[path[-1]]
    elif kind == "shift":
        container[path[-1]] = current + int(rng.choice([-1, 1]))
    else:
        # a valid number where any number is valid (a coefficient, a valid range) is another model, not a corruption
        free = path[0] == "coefficients" or path[:2] in FREE or (path[0] == "sources" and path[-1] in ("C1", "C2"))
        choices = [v for v in HOSTILE if not (free and (v == -1 or v == [1, 2]))]
        container[path[-1]] = choices[rng.integers(len(choices))]
    return mutated


def grouped_decisions(model, temps):
    """Load as replay and export do, replay the rule and render every target; the groups and predictions."""
    loaded = ModelFile.from_dict(model)
    replay = SwitchingRule(loaded).replay(temps)
    for target in TARGETS:
        render(loaded, target)
    return replay.group, replay.prediction_um


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=0)
    kind = parser.add_mutually_exclusive_group()
    kind.add_argument("--derived", action="store_true", help="mutate a model with derived inputs")
    kind.add_argument("--position", action="store_true", help="mutate the position and dead-band sections")
    kind.add_argument("--screw", action="store_true", help="mutate a ball-screw model file")
    kind.add_argument("--recalibration", action="store_true", help="mutate the recalibration section")
    args = parser.parse_args(argv)
    if args.screw:
        model, temps = screw_model()
        outcome = screw_decisions
    elif args.recalibration:
        model, temps = recalibration_model()
        outcome = recalibration_decisions
    else:
        model, temps = (derived_model if args.derived else position_model if args.position else base_model)()
        outcome = grouped_decisions
    reference = outcome(model, temps)
    sections = ("position", "dead_band") if args.position else ("recalibration",) if args.recalibration else None
    all_paths = [p for p in paths(model) if p and (sections is None or p[0] in sections)]
    rng = np.random.default_rng(args.seed)
    counts: Counter[str] = Counter()
    examples: dict[str, str] = {}
    start = time.perf_counter()
    for _ in range(args.count):
        mutated = json.loads(json.dumps(mutate(model, all_paths, rng)))
        try:
            result = outcome(mutated, temps)
        except InputError as exc:
            counts["refused (one line)" if "\n" not in str(exc) else "refused (several lines)"] += 1
            continue
        except Exception as exc:  # a traceback on the command line
            counts["crashed"] += 1
            examples.setdefault("crashed", f"{type(exc).__name__}: {exc}")
            continue
        section = mutated.get("recalibration") if args.recalibration else None
        if same(result, reference):
            counts["accepted, identical decisions"] += 1
        elif (default := without_optional_switching(model, mutated)) is not None and same(
            result, outcome(default, temps)
        ):
            counts["accepted, another valid model"] += 1  # an optional switching key left out: its default
        elif args.recalibration and section is None:
            counts["accepted, another valid model"] += 1  # the optional section left out: a model without checks
        elif args.recalibration and same(result, outcome({**mutated, "recalibration": with_defaults(section)}, temps)):
            counts["accepted, another valid model"] += 1  # an optional key left out: its default, written or not
        else:
            counts["exported although invalid"] += 1
            examples.setdefault("exported although invalid", json.dumps(mutated)[:300])
    seconds = time.perf_counter() - start
    kind = (
        "a ball-screw model file"
        if args.screw
        else "the recalibration section of a p = 3 model file, replayed with probe checks"
        if args.recalibration
        else "the position and dead-band sections of a position model file"
        if args.position
        else "a p = 2 model file with derived inputs"
        if args.derived
        else "a p = 3 model file"
    )
    print(f"{args.count} mutations of {kind} (seed {args.seed}) in {seconds:.1f} s")
    shown = ("refused (one line)", "refused (several lines)", "accepted, identical decisions")
    for key in (*shown, "accepted, another valid model"):
        print(f"  {key:32s} {counts[key]}")
    print(f"  {'crashed (traceback)':32s} {counts['crashed']}")
    print(f"  {'exported although invalid':32s} {counts['exported although invalid']}")
    for key, text in examples.items():
        print(f"  first {key}: {text}")
    return 1 if counts["crashed"] or counts["exported although invalid"] or counts["refused (several lines)"] else 0


if __name__ == "__main__":
    sys.exit(main())
