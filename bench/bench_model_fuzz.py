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

from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.export import TARGETS, render
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor
from groupfit.runtime import SwitchingRule

DATA = Path(__file__).resolve().parents[1] / "datasets" / "synthetic_cycle.csv"
DERIVED_DATA = Path(__file__).resolve().parents[1] / "datasets" / "diag_ambient_model.csv"
HOSTILE = [None, True, False, "text", [], {}, [1, 2], math.nan, math.inf, -math.inf, 1e308, -1e308, -1]
STRUCTURAL = {"p", "n", "n_samples", "breaks", "hard_groups", "soft_groups", "criterion_index", "windows"}
"""Whole numbers shifted by one (not those of derived inputs: a delay of 4 samples is another valid model)."""


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
        free = path[0] == "coefficients" or path[:2] == ("switching", "source_ranges")
        choices = [v for v in HOSTILE if not (free and (v == -1 or v == [1, 2]))]
        container[path[-1]] = choices[rng.integers(len(choices))]
    return mutated


def decisions(model, temps):
    replay = SwitchingRule(model).replay(temps)
    return replay.group, replay.prediction_um


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--derived", action="store_true", help="mutate a model with derived inputs")
    args = parser.parse_args(argv)
    model, temps = derived_model() if args.derived else base_model()
    groups0, prediction0 = decisions(model, temps)
    all_paths = [p for p in paths(model) if p]
    rng = np.random.default_rng(args.seed)
    counts: Counter[str] = Counter()
    examples: dict[str, str] = {}
    start = time.perf_counter()
    for _ in range(args.count):
        mutated = json.loads(json.dumps(mutate(model, all_paths, rng)))
        try:
            loaded = ModelFile.from_dict(mutated)
            groups, prediction = decisions(loaded, temps)
            for target in TARGETS:
                render(loaded, target)
        except InputError as exc:
            counts["refused (one line)" if "\n" not in str(exc) else "refused (several lines)"] += 1
            continue
        except Exception as exc:  # a traceback on the command line
            counts["crashed"] += 1
            examples.setdefault("crashed", f"{type(exc).__name__}: {exc}")
            continue
        if np.array_equal(groups, groups0) and np.array_equal(prediction, prediction0):
            counts["accepted, identical decisions"] += 1
        else:
            counts["exported although invalid"] += 1
            examples.setdefault("exported although invalid", json.dumps(mutated)[:300])
    seconds = time.perf_counter() - start
    kind = "a p = 2 model file with derived inputs" if args.derived else "a p = 3 model file"
    print(f"{args.count} mutations of {kind} (seed {args.seed}) in {seconds:.1f} s")
    for key in ("refused (one line)", "refused (several lines)", "accepted, identical decisions"):
        print(f"  {key:32s} {counts[key]}")
    print(f"  {'crashed (traceback)':32s} {counts['crashed']}")
    print(f"  {'exported although invalid':32s} {counts['exported although invalid']}")
    for key, text in examples.items():
        print(f"  first {key}: {text}")
    return 1 if counts["crashed"] or counts["exported although invalid"] or counts["refused (several lines)"] else 0


if __name__ == "__main__":
    sys.exit(main())
