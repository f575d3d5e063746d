"""Does ``groupfit diagnose`` name the effect a model misses, on runs from an independent simulator?

The runs come from ``bench/independent_machine.py``, a lumped RC thermal
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
diagnosis says so (``improved is False``); otherwise FAIL with a short reason.
It is a measurement, not a test: it exits 0 whatever the verdicts.

    python bench/bench_diagnose_independent.py [--only NAME ...] [--json FILE] [--reference none|default] [--joint]

The whole set runs in about 10 s on two cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from independent_machine import Scenario, oracle_rms_um, scenario_specs, scenarios  # noqa: E402

from groupfit.data import load_run  # noqa: E402
from groupfit.diagnose import diagnose  # noqa: E402
from groupfit.modelfile import model_to_dict  # noqa: E402
from groupfit.models.grouped import GroupedRegressor  # noqa: E402
from groupfit.reference import default_reference, with_reference  # noqa: E402
from groupfit.runtime import replay_groups  # noqa: E402

MIN_FALL = 0.40
"""The validation RMS must fall by at least this fraction for an OK."""


def base_model(scenario: Scenario, reference: str = "none"):
    """The MLR on the sensors fitted on the modelling run, as a model file dict, and the two runs.

    ``reference="default"``: the inputs taken as rises over ``T_amb`` when the run has it, as
    ``groupfit fit`` does without ``--reference``; ``"none"``: absolute readings.
    """
    modelling = load_run(scenario.modelling, temps=scenario.temps, error="error_um", name="modelling")
    validation = load_run(
        scenario.validation, temps=scenario.temps, error="error_um", name="validation", allow_nonfinite=True
    )
    fitted = modelling
    if reference == "default":
        fitted = with_reference(modelling, default_reference(modelling.frame))
    model = model_to_dict(GroupedRegressor(p=0).fit(fitted.temps, fitted.error), fitted)
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
    return text


def verdict(scenario: Scenario, added: list[dict], before: float, after: float, improved) -> str:
    """OK / worse, reported so / FAIL (reason)."""
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
    return f"FAIL: validation fell only {100 * fall:.0f} %"


def measure(scenario: Scenario, reference: str = "none", joint: bool = False) -> dict:
    """Fit, diagnose and score one scenario (``joint``: as ``diagnose --select joint``)."""
    start = time.perf_counter()
    model, modelling, validation = base_model(scenario, reference)
    result = diagnose(model, modelling, validation, live_rule=replay_groups, select_jointly=joint)
    seconds = time.perf_counter() - start
    added = [
        {k: c.to_dict()[k] for k in ("column", "transform", "tau_s", "exponent", "delay_samples", "description")}
        for c in result.added
    ]
    before = float(result.before["validate"]["rms_um"])
    after = float(result.after["validate"]["rms_um"])
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
        "oracle_rms_um": oracle_rms_um(scenario),
        "verdict": verdict(scenario, added, before, after, result.improved),
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
        further = "; ".join(describe(a) for a in r["added"][1:]) or "–"
        rms = f"{r['validation_rms_before_um']:.3g} → {r['validation_rms_after_um']:.3g} ({r['change_pct']:+.0f} %)"
        lines.append(
            f"| {r['scenario']} | {truth}: {r['truth']} | {first} | {further} | {rms} | "
            f"{r['oracle_rms_um']:.3g} | {r['verdict']} |"
        )
    return "\n".join(lines)


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
    args = parser.parse_args(argv)
    known = [spec.name for spec in scenario_specs()]
    if args.only and any(name not in known for name in args.only):
        parser.error(f"--only: known scenarios are {', '.join(known)}")
    start = time.perf_counter()
    rows = []
    for scenario in scenarios(args.only):
        rows.append(measure(scenario, args.reference, args.joint))
        r = rows[-1]
        print(f"{r['scenario']:<28} {r['seconds']:5.1f} s  {r['verdict']}", file=sys.stderr, flush=True)
    print(table(rows))
    ok = sum(r["verdict"] == "OK" for r in rows)
    worse = sum(r["verdict"].startswith("worse") for r in rows)
    total = time.perf_counter() - start
    print(f"\n{ok} OK, {worse} worse and reported so, {len(rows) - ok - worse} FAIL of {len(rows)}; {total:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        print(f"rows written to {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
