"""Does ``groupfit diagnose`` name the effect a model misses, on runs from an independent simulator?

The runs come from ``tests/support/independent_machine.py``, a lumped RC thermal
network of a machine tool written with numpy/scipy only (no code shared with
``groupfit.synthetic`` or ``groupfit.fe``). Each scenario is a modelling run
and a validation run with one known missing effect (an unsensed part that
follows the air, a pump, the spindle speed through its heat law …), two
effects (the physical variants, whose unsensed part also follows the air) or
none. For each scenario the bench

1. fits the base model as ``groupfit fit --p 0 --search exact --reference none``
   does: the MLR on the sensor temperatures of the modelling run
   (``--reference default``: on their rises over ``T_amb``, the fit's default);
2. runs ``groupfit diagnose`` on the modelling run with the validation run
   (effects chosen on the modelling run only, judged on the validation run
   through the run-time rule);
3. prints the first effect added, the further ones, the validation RMS before
   → after, and the oracle: least squares on the sensors plus the true hidden
   node (noise-free), fitted on the modelling run and scored on the validation run.

Verdict: OK when the first effect's column carries the true effect and the
validation RMS falls by at least 40 %, or when nothing is missing and nothing
was added; "worse, reported so" when the validation got worse and the
diagnosis says so (``improved is False``); "out of reach" when the first
effect is the true one, the validation got better but by less than 40 %, and
the oracle itself does not reach 40 % below the base model (no diagnosis
could); otherwise FAIL with a short reason.
It is a measurement, not a test: it exits 0 whatever the verdicts.

    python bench/bench_diagnose_independent.py [--only NAME ...] [--json FILE] [--reference none|default] [--joint]
        [--keep-reference] [--p P] [--random N [--first-seed S] [--truth absolute|rises]]

``--random N`` replaces the fixed set by N randomised scenarios (:func:`support.independent_machine.random_spec`): the
missing effect cycles through an ambient, a pump, a speed, an on/off spindle and nothing; every run is a new
workshop day (ambient level 18 … 24 °C, swing, phase, HVAC step, door), with new schedules, sampling period and
time constant. ``--truth rises`` makes the error follow the parts' rises over the air instead of their
temperatures over 20 °C: with ``--reference default`` the two together show whether diagnose's check of the
reference sensor drops it only where it is wrong.

The whole set runs in about 10 s on two cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from support.independent_machine import (  # noqa: E402
    RANDOM_KINDS,
    Scenario,
    oracle_rms_um,
    random_scenarios,
    scenario_specs,
    scenarios,
)

from groupfit.data import load_run  # noqa: E402
from groupfit.diagnose import diagnose  # noqa: E402
from groupfit.models.grouped import GroupedRegressor  # noqa: E402
from groupfit.reference import default_reference, with_reference  # noqa: E402
from groupfit.runtime import replay_groups  # noqa: E402

MIN_FALL = 0.40
"""The validation RMS must fall by at least this fraction for an OK."""


def base_model(scenario: Scenario, reference: str = "none", p: int = 0):
    """The MLR on the sensors fitted on the modelling run, as a model file dict, and the two runs.

    ``reference="default"``: the inputs taken as rises over ``T_amb`` when the run has it, as
    ``groupfit fit`` does without ``--reference``; ``"none"``: absolute readings. ``p > 0``: a grouped
    model with p hard breaks (the genetic algorithm, seed 0) instead of the MLR.
    """
    modelling = load_run(scenario.modelling, temps=scenario.temps, error="error_um", name="modelling")
    validation = load_run(
        scenario.validation, temps=scenario.temps, error="error_um", name="validation", allow_nonfinite=True
    )
    fitted = modelling
    if reference == "default":
        fitted = with_reference(modelling, default_reference(modelling.frame))
    model = GroupedRegressor(p=p, random_state=0).fit(fitted.temps, fitted.error).to_model_file(fitted).to_dict()
    return model, modelling, validation


def describe(effect: dict) -> str:
    """``column transform τ=… [heat law ^k] [delay n]`` of one added effect."""
    text = effect["column"] + (" heat-law" if effect["exponent"] else "") + " " + effect["transform"]
    tau = effect["tau_s"]
    if tau:
        text += f" τ={tau / 60:g}min" if tau < 3600 else f" τ={tau / 3600:g}h"
    if effect["exponent"]:
        text += f" ^{effect['exponent']:.3g}"
    if effect["delay_samples"]:
        text += f" delay {effect['delay_samples']}"
    if effect.get("over_reference"):
        text += f" over {effect['over_reference']}"
    return text


def verdict(scenario: Scenario, added: list[dict], before: float, after: float, improved, oracle: float = 0.0) -> str:
    """OK / worse, reported so / out of reach / FAIL (reason); ``oracle``: the oracle's validation RMS."""
    fall = (before - after) / before
    if not scenario.missing:
        if not added:
            return "OK"
    elif added and added[0]["column"] in scenario.missing and fall >= MIN_FALL:
        return "OK"
    if after > before and improved is False:
        return "worse, reported so"
    if not scenario.missing:
        return f"FAIL: added {added[0]['column']} with nothing missing"
    if not added:
        return "FAIL: nothing added"
    if added[0]["column"] not in scenario.missing:
        return f"FAIL: first effect on {added[0]['column']}, not {' / '.join(scenario.missing)}"
    if after < before and oracle > (1.0 - MIN_FALL) * before:
        return f"out of reach: fell {100 * fall:.0f} %, the oracle {100 * (before - oracle) / before:.0f} %"
    return f"FAIL: validation fell only {100 * fall:.0f} %"


def measure(
    scenario: Scenario, reference: str = "none", joint: bool = False, keep_reference: bool = False, p: int = 0
) -> dict:
    """Fit, diagnose and score one scenario (``joint``: as ``diagnose --select joint``; ``keep_reference``: as
    ``diagnose --keep-reference``; ``p``: hard breaks of the base model)."""
    start = time.perf_counter()
    model, modelling, validation = base_model(scenario, reference, p)
    result = diagnose(
        model, modelling, validation, live_rule=replay_groups, select_jointly=joint, check_reference=not keep_reference
    )
    seconds = time.perf_counter() - start
    added = [
        {
            k: c.to_dict()[k]
            for k in ("column", "transform", "tau_s", "exponent", "delay_samples", "over_reference", "description")
        }
        for c in result.added
    ]
    before = float(result.before["validate"]["rms_um"])
    after = float(result.after["validate"]["rms_um"])
    oracle = oracle_rms_um(scenario)
    return {
        "scenario": scenario.name,
        "truth": scenario.truth,
        "missing": list(scenario.missing),
        "temps": scenario.temps,
        "added": added,
        "validation_rms_before_um": before,
        "validation_rms_after_um": after,
        "change_pct": 100 * (after - before) / before,
        "improved": result.improved,
        "reference_dropped": bool(result.reference and result.reference.dropped),
        "oracle_rms_um": oracle,
        "verdict": verdict(scenario, added, before, after, result.improved, oracle),
        "report_first_line": result.summary().splitlines()[0],
        "notes": scenario.notes,
        "seconds": round(seconds, 2),
    }


def table(rows: list[dict]) -> str:
    """The Markdown table of the rows."""
    lines = [
        "| scenario | truth | first effect added | further effects | validation RMS µm | oracle µm | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        truth = " + ".join(f"`{c}`" for c in r["missing"]) or "nothing"
        first = describe(r["added"][0]) if r["added"] else "nothing"
        if r["reference_dropped"]:
            first = f"(T_amb reference dropped) {first}"
        further = "; ".join(describe(a) for a in r["added"][1:]) or "–"
        rms = f"{r['validation_rms_before_um']:.3g} → {r['validation_rms_after_um']:.3g} ({r['change_pct']:+.0f} %)"
        lines.append(
            f"| {r['scenario']} | {truth}: {r['truth']} | {first} | {further} | {rms} | "
            f"{r['oracle_rms_um']:.3g} | {r['verdict']} |"
        )
    return "\n".join(lines)


def verdict_counts(rows: list[dict]) -> tuple[int, int, int, int]:
    """How many rows are OK, worse and reported so, out of reach, FAIL."""
    ok = sum(r["verdict"] == "OK" for r in rows)
    worse = sum(r["verdict"].startswith("worse") for r in rows)
    unreachable = sum(r["verdict"].startswith("out of reach") for r in rows)
    return ok, worse, unreachable, len(rows) - ok - worse - unreachable


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", metavar="NAME", help="run only these scenarios")
    parser.add_argument("--json", metavar="FILE", help="write the rows to FILE")
    parser.add_argument(
        "--reference",
        choices=("none", "default"),
        default="none",
        help="the base model on absolute readings (none, as --reference none) or on rises over T_amb (default)",
    )
    parser.add_argument("--joint", action="store_true", help="diagnose as --select joint does")
    parser.add_argument(
        "--keep-reference", action="store_true", help="diagnose as --keep-reference does (no check of T_amb)"
    )
    parser.add_argument(
        "--random",
        type=int,
        metavar="N",
        help="instead of the fixed set, N randomised scenarios r0 … (a missing effect by seed, a new workshop "
        "day, schedules, sampling and time constant each)",
    )
    parser.add_argument("--first-seed", type=int, default=0, help="first seed of --random (default 0)")
    parser.add_argument(
        "--p", type=int, default=0, help="hard breaks of the base model (default 0: the MLR; > 0: a grouped model)"
    )
    parser.add_argument(
        "--truth",
        choices=("absolute", "rises"),
        default="absolute",
        help="--random: the error follows the parts' temperatures over 20 °C (absolute) or their rises over the air",
    )
    args = parser.parse_args(argv)
    known = [spec.name for spec in scenario_specs()]
    if args.only and any(name not in known for name in args.only):
        parser.error(f"--only: known scenarios are {', '.join(known)}")
    start = time.perf_counter()
    rows = []
    chosen = random_scenarios(args.random, args.first_seed, args.truth) if args.random else scenarios(args.only)
    for scenario in chosen:
        rows.append(measure(scenario, args.reference, args.joint, args.keep_reference, args.p))
        r = rows[-1]
        print(f"{r['scenario']:<28} {r['seconds']:5.1f} s  {r['verdict']}", file=sys.stderr, flush=True)
    print(table(rows))
    if args.random:
        print(
            "\n| missing | OK | worse, reported so | out of reach | FAIL | reference dropped |"
            "\n|---|---|---|---|---|---|"
        )
        for kind in RANDOM_KINDS:
            of_kind = [r for r in rows if r["scenario"].endswith("_" + kind)]
            ok, worse, unreachable, fail = verdict_counts(of_kind)
            dropped = sum(r["reference_dropped"] for r in of_kind)
            print(f"| {kind} | {ok} | {worse} | {unreachable} | {fail} | {dropped} of {len(of_kind)} |")
    ok, worse, unreachable, fail = verdict_counts(rows)
    total = time.perf_counter() - start
    print(
        f"\n{ok} OK, {worse} worse and reported so, {unreachable} out of reach, {fail} FAIL of {len(rows)}; "
        f"{total:.0f} s"
    )
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        print(f"rows written to {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
