"""``groupfit diagnose``: residual → missing effect → augmented model → error before/after."""

from __future__ import annotations

import argparse
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.commands.common import check_output_dir, report_stream, write_json
from groupfit.data import DEFAULT_TIME, Run, load_run
from groupfit.diagnose import DiagnosisResult, diagnose
from groupfit.diagnose.candidates import HEAT_EXPONENT
from groupfit.diagnose.loop import MIN_EFFECT_RMS_UM, MIN_SCORE, joint_name
from groupfit.errors import InputError
from groupfit.modelfile import load_model, save_model
from groupfit.sweep.selection import SELECTION_METHODS


def add_parser(verbs) -> None:
    parser = verbs.add_parser("diagnose", help="trace a model's residual on measured data to a missing effect")
    parser.add_argument("model", metavar="MODEL", help="model file (groupfit-model/1 JSON)")
    parser.add_argument(
        "--data",
        required=True,
        nargs="+",
        metavar="RUN",
        help="measured run(s) (CSV, XLSX or Parquet): candidates are chosen on them; several runs are held out "
        "one at a time",
    )
    parser.add_argument("--validate", nargs="+", metavar="RUN", help="other run(s), only to judge the result")
    parser.add_argument("--time", default=DEFAULT_TIME, metavar="COLUMN", help="time column (default time_s)")
    parser.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' for stdout)")
    parser.add_argument("--out", default="groupfit-out", metavar="DIR", help="folder for figures and the new model")
    parser.add_argument(
        "--min-score",
        type=float,
        default=MIN_SCORE,
        metavar="F",
        help=f"least out-of-sample share of the residual an effect must explain (default {MIN_SCORE})",
    )
    parser.add_argument(
        "--min-effect",
        type=float,
        default=MIN_EFFECT_RMS_UM,
        metavar="UM",
        help=f"least residual RMS in µm an effect must remove (default {MIN_EFFECT_RMS_UM})",
    )
    parser.add_argument(
        "--heat-exponent",
        type=heat_exponent,
        default=HEAT_EXPONENT,
        metavar="K|fit",
        help="exponent k of the bearing-heat law (n/scale)^k for speed columns (default 5/3), or 'fit'",
    )
    parser.add_argument(
        "--own-transforms",
        action="store_true",
        help="also try low-passes, derivatives and delays of the model's own inputs (under the every-fold test)",
    )
    parser.add_argument(
        "--select",
        choices=SELECTION_METHODS,
        help="first re-select the model's inputs on held-out conditions (for a model that over-fits)",
    )
    parser.set_defaults(handler=run_diagnose)


def heat_exponent(text: str) -> float | str:
    if text == "fit":
        return text
    try:
        value = float(Fraction(text))
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"{text!r}: give a number such as 5/3 or 1.67, or 'fit'") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{text!r}: the exponent must be > 0")
    return value


def load_measured(path: str, model: dict[str, Any], time: str) -> Run:
    derived = {d["name"] for d in model.get("derived_inputs", [])}
    measured = [t for t in model["temps"] if t not in derived]
    run = load_run(path, temps=measured, time=time, error=model["error"], allow_nonfinite=True)
    period = float(model["sampling_period_s"])
    if abs(run.period - period) > 0.01 * period:
        raise InputError(
            f"{run.source}: sampled every {run.period:g} s but the model every {period:g} s; "
            "resample the run to the model's period"
        )
    bad = ~np.isfinite(run.error)
    if bad.any():
        raise InputError(
            f"{run.source}: row {int(np.flatnonzero(bad)[0]) + 1}, error column '{model['error']}' is not finite "
            f"({int(bad.sum())} rows); the residual needs the measured error: drop those rows"
        )
    return run


def run_diagnose(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    data = [load_measured(path, model, args.time) for path in args.data]
    validate = [load_measured(path, model, args.time) for path in args.validate or []]
    out_dir = check_output_dir(args.out)
    from groupfit.runtime import replay_groups

    start = model
    selection = None
    if args.select:
        from groupfit.diagnose.select import select_base_model

        start, selection = select_base_model(model, data, args.select)
    result = diagnose(
        start,
        data,
        validate or None,
        live_rule=replay_groups,
        min_score=args.min_score,
        min_effect_rms_um=args.min_effect,
        heat_exponent=args.heat_exponent,
        own_transforms=args.own_transforms,
    )
    if selection is not None:
        result = with_original_baseline(result, model, data, validate, replay_groups, selection)

    model_path = Path(args.model)
    written = []
    if result.added or selection is not None:
        model_path = out_dir / "model_augmented.json"
        save_model(result.model, model_path)
        written.append(model_path)
    from groupfit.plots import plot_diagnosis

    figure = out_dir / "diagnose.png"
    runs = {"data": data, **({"validate": validate} if validate else {})}
    plot_diagnosis(result, runs, figure)
    written.append(figure)

    write_json(args.json, result_json(result, model_path))
    print(diagnosis_report(result, data, validate, written), file=report_stream(args))
    return 0


def with_original_baseline(result, model, data, validate, live_rule, selection) -> DiagnosisResult:
    """Report before/after against the model the user gave, not the re-selected one."""
    from groupfit.diagnose.loop import metrics_of, residual_checks, stacked_residual

    runs = {"data": data, **({"validate": validate} if validate else {})}
    before = {key: stacked_residual(model, rs, live_rule) for key, rs in runs.items()}
    result.residuals_before = before
    result.before = {key: metrics_of(r) for key, r in before.items()}
    result.checks_before = residual_checks(before["data"], np.arange(len(before["data"])) * data[0].period)
    result.selection = {**selection, "of": len(model["temps"])}
    return result


def result_json(result: DiagnosisResult, model_path: Path) -> dict[str, Any]:
    return {
        "candidates": [c.to_dict() for c in result.candidates],
        "added": [c.to_dict() for c in result.added],
        "steps": [s.to_dict() for s in result.steps],
        "refused": [r.to_dict() for r in result.refused],
        "folds": result.folds,
        "base_model": result.base_check,
        "selection": getattr(result, "selection", None),
        "before": result.before,
        "after": result.after,
        "improved": result.improved,
        "checks": {"before": result.checks_before, "after": result.checks_after},
        "notes": result.notes,
        "model": str(model_path),
    }


def column_words(column: str) -> str:
    """What a column is, in words, for the report."""
    if column.lower() in ("t_amb", "ambient", "t_ambient") or "amb" in column.lower():
        return f"ambient temperature `{column}`"
    if column.startswith("src_") and column.endswith("_on"):
        return f"heat source '{column[4:-3]}' (on/off `{column}`)"
    if column == "spindle_on":
        return f"spindle heat, a part that lags it (`{column}`)"
    if "speed" in column or "rpm" in column:
        return f"spindle speed, a part that lags it (`{column}`)"
    return f"column `{column}`"


def change_words(before: float, after: float) -> str:
    """``RMS 11 → 4.4 µm (60 % lower)`` or ``(80 % higher)``."""
    if before <= 0:
        return f"{before:.3g} → {after:.3g} µm"
    change = 100.0 * (after - before) / before
    if abs(change) < 0.5:
        words = "unchanged"
    else:
        words = f"{abs(change):.0f} % {'higher' if change > 0 else 'lower'}"
    return f"{before:.3g} → {after:.3g} µm ({words})"


def diagnosis_report(result: DiagnosisResult, data: list[Run], validate: list[Run], written) -> str:
    lines = []
    judge = "validate" if validate else "data"
    judged = joint_name(validate) if validate else joint_name(data)
    b, a = result.before[judge], result.after[judge]
    changed = bool(result.added) or getattr(result, "selection", None) is not None
    if result.improved is False or (validate and changed and a["rms_um"] >= b["rms_um"]):
        lines.append(
            f"the augmented model is worse on {judged}: {b['rms_um']:.3g} → {a['rms_um']:.3g} µm RMS; not recommended"
        )
    selection = getattr(result, "selection", None)
    if selection is not None:
        lines.append(
            f"inputs re-selected by {selection['method']} on held-out conditions: {', '.join(selection['inputs'])} "
            f"({len(selection['inputs'])} of {selection['of']}); before/after compare with the model as given"
        )
    if result.added:
        for step in result.steps:
            c = step.candidate
            better = f"{c.folds_improved * len(c.fold_ratios):.0f} of {len(c.fold_ratios)}"
            held_out = change_words(step.held_out_rms_before, step.held_out_rms_after)
            lines.append(
                f"missing effect: {column_words(c.feature.column)}, {c.feature.describe()} "
                f"(removes {100 * c.score:.0f} % of the held-out error, better on {better} held-out folds; "
                f"held-out RMS {held_out})"
            )
            if step.alternatives:
                others = "; ".join(f"{a.feature.column} {a.feature.describe()}" for a in step.alternatives[:3])
                lines.append(f"  as well explained (within one standard error) by: {others}")
        lines.append(
            f"{'validation' if validate else 'measured'} run {judged}: RMS {change_words(b['rms_um'], a['rms_um'])}, "
            f"max {b['max_um']:.3g} → {a['max_um']:.3g} µm"
        )
        lines.append("each effect was added as one more input of every group, the hard breaks kept, groups refitted")
    else:
        lines.append("nothing missing: no candidate explains a significant part of the held-out error; no effect added")
    lines.append(f"held out: {result.folds}")
    for refusal in result.refused[:5]:
        c = refusal.candidate
        lines.append(f"refused: {c.feature.column} {c.feature.describe()} (score {c.score:.2f}): {refusal.reason}")
    lines.append("")
    lines.append(f"{'candidate':<24} {'transform':<40} {'score':>6} {'folds':>6} {'removes RMS µm':>15}")
    for c in result.candidates[:10]:
        lines.append(
            f"{c.feature.column:<24} {c.feature.describe():<40} {c.score:>6.3f} "
            f"{c.folds_improved * len(c.fold_ratios):>3.0f}/{len(c.fold_ratios):<2} {c.explained_rms_um:>15.3g}"
        )
    lines.append("")
    for key in result.before:
        runs = data if key == "data" else validate
        b, a = result.before[key], result.after[key]
        lines.append(
            f"{key:<9} {joint_name(runs)}: RMS {change_words(b['rms_um'], a['rms_um'])}, max {b['max_um']:.4g} → "
            f"{a['max_um']:.4g} µm, R {b['R_um']:.4g} → {a['R_um']:.4g} µm"
        )
    lb_b, lb_a = result.checks_before["ljung_box"], result.checks_after["ljung_box"]
    dr_b, dr_a = result.checks_before["drift"], result.checks_after["drift"]
    lines.append(
        f"residual on {joint_name(data)}: Ljung–Box Q({lb_b['lags']}) {lb_b['Q']:.0f} → {lb_a['Q']:.0f}; "
        f"drift {dr_b['slope_um_per_h']:.3g} → {dr_a['slope_um_per_h']:.3g} µm/h "
        f"(HAC p {dr_b['p_value']:.2g} → {dr_a['p_value']:.2g})"
    )
    lines += [f"note: {n}" for n in result.notes]
    lines.append("wrote   " + ", ".join(str(p) for p in written))
    return "\n".join(lines)
