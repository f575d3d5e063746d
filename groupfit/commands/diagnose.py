"""``groupfit diagnose``: residual → missing effect → augmented model → error before/after."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.commands.common import check_output_dir, report_stream, write_json
from groupfit.data import DEFAULT_TIME, Run, load_run
from groupfit.diagnose import DiagnosisResult, diagnose
from groupfit.diagnose.loop import MIN_EFFECT_RMS_UM, MIN_SCORE
from groupfit.errors import InputError
from groupfit.modelfile import load_model, save_model


def add_parser(verbs) -> None:
    parser = verbs.add_parser("diagnose", help="trace a model's residual on measured data to a missing effect")
    parser.add_argument("model", metavar="MODEL", help="model file (groupfit-model/1 JSON)")
    parser.add_argument("--data", required=True, metavar="CSV", help="measured run: candidates are chosen on it")
    parser.add_argument("--validate", metavar="CSV", help="another run, only to judge the result")
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
    parser.set_defaults(handler=run_diagnose)


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
    data = load_measured(args.data, model, args.time)
    validate = load_measured(args.validate, model, args.time) if args.validate else None
    out_dir = check_output_dir(args.out)
    from groupfit.runtime import replay_groups

    result = diagnose(
        model,
        data,
        validate,
        live_rule=replay_groups,
        min_score=args.min_score,
        min_effect_rms_um=args.min_effect,
    )

    model_path = Path(args.model)
    written = []
    if result.added:
        model_path = out_dir / "model_augmented.json"
        save_model(result.model, model_path)
        written.append(model_path)
    from groupfit.plots import plot_diagnosis

    figure = out_dir / "diagnose.png"
    runs = {"data": data, **({"validate": validate} if validate is not None else {})}
    plot_diagnosis(result, runs, figure)
    written.append(figure)

    write_json(args.json, result_json(result, model_path))
    print(diagnosis_report(result, data, validate, written), file=report_stream(args))
    return 0


def result_json(result: DiagnosisResult, model_path: Path) -> dict[str, Any]:
    return {
        "candidates": [c.to_dict() for c in result.candidates],
        "added": [c.to_dict() for c in result.added],
        "before": result.before,
        "after": result.after,
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


def diagnosis_report(result: DiagnosisResult, data: Run, validate: Run | None, written) -> str:
    lines = []
    judge = "validate" if validate is not None else "data"
    judged = validate.name if validate is not None else data.name
    if result.added:
        for c in result.added:
            lines.append(
                f"missing effect: {column_words(c.feature.column)}, {c.feature.describe()} "
                f"(explains {100 * c.score:.0f} % of the residual out of sample)"
            )
        b, a = result.before[judge], result.after[judge]
        lines.append(
            f"{'validation' if validate is not None else 'measured'} run {judged}: RMS {b['rms_um']:.3g} → "
            f"{a['rms_um']:.3g} µm, max {b['max_um']:.3g} → {a['max_um']:.3g} µm "
            f"({100 * (1 - a['rms_um'] / b['rms_um']):.0f} % lower RMS)"
        )
        lines.append("each effect was added as one more input of every group, the hard breaks kept, groups refitted")
    else:
        lines.append(
            "nothing missing: no candidate explains a significant part of the residual; the model is unchanged"
        )
    lines.append("")
    lines.append(f"{'candidate':<24} {'transform':<28} {'score':>6} {'removes RMS µm':>15}")
    for c in result.candidates[:10]:
        lines.append(f"{c.feature.column:<24} {c.feature.describe():<28} {c.score:>6.3f} {c.explained_rms_um:>15.3g}")
    lines.append("")
    for key in result.before:
        run = data if key == "data" else validate
        b, a = result.before[key], result.after[key]
        lines.append(
            f"{key:<9} {run.name}: RMS {b['rms_um']:.4g} → {a['rms_um']:.4g} µm, max {b['max_um']:.4g} → "
            f"{a['max_um']:.4g} µm, R {b['R_um']:.4g} → {a['R_um']:.4g} µm"
        )
    lb_b, lb_a = result.checks_before["ljung_box"], result.checks_after["ljung_box"]
    dr_b, dr_a = result.checks_before["drift"], result.checks_after["drift"]
    lines.append(
        f"residual on {data.name}: Ljung–Box Q({lb_b['lags']}) {lb_b['Q']:.0f} → {lb_a['Q']:.0f}; "
        f"drift {dr_b['slope_um_per_h']:.3g} → {dr_a['slope_um_per_h']:.3g} µm/h "
        f"(HAC p {dr_b['p_value']:.2g} → {dr_a['p_value']:.2g})"
    )
    lines += [f"note: {n}" for n in result.notes]
    lines.append("wrote   " + ", ".join(str(p) for p in written))
    return "\n".join(lines)
