"""``replay`` and ``export`` of a ball-screw model file (groupfit.screw.deploy, groupfit.screw.export)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from groupfit.commands import common
from groupfit.commands.export_options import target_options
from groupfit.errors import InputError
from groupfit.metrics import error_metrics
from groupfit.screw.deploy import ScrewLaw, choose_source
from groupfit.screw.export import SCREW_TARGETS, check_screw_target, render_screw
from groupfit.screw.modelfile import load_model
from groupfit.screw.plots import plot_error
from groupfit.screw.runs import PROBE_COLUMN, load_screw_run


def screw_law(args: argparse.Namespace) -> ScrewLaw:
    model = load_model(args.model)
    return ScrewLaw.from_model(model, choose_source(model, getattr(args, "source", None), str(args.model)))


def run_screw_replay(args: argparse.Namespace) -> int:
    """The law sample by sample on a run: the time since its first sample, the probe position, τ0 (line law)."""
    if args.precision != "double":
        raise InputError(f"--precision {args.precision}: the ball-screw law is deployed in double precision only")
    out_dir = common.plan_outputs(args, args.model, args.data, folder=args.out, files=("replay.png",))
    law = screw_law(args)
    columns = {"time": args.time, "error": args.error, "scored_only": True}
    run = load_screw_run(args.data, **common.clock_options(args), **common.range_options(args), **columns)
    common.print_notes([run.run], common.report_stream(args))
    if run.probe_x is None:
        raise InputError(
            f"{run.source}: column '{PROBE_COLUMN}' not found; the ball-screw law gives the error at the probe "
            "position (m from the source) of every sample"
        )
    tau0 = None
    if law.law == "line":
        model = load_model(args.model)
        tau0 = model.reference_rise(run.rises, run.positions, run.source)
    codes, prediction = law.replay(run.time, run.probe_x, tau0)
    result = screw_replay_result(law, run, codes, prediction, str(args.model))
    written = []
    if out_dir is not None and run.error is not None:
        figure = out_dir / "replay.png"
        plot_error(run.time, run.error, {"run-time law": prediction}, figure, title=f"{run.name}: {law.source}")
        written.append(figure)
    common.finish_outputs(args, screw_replay_report(result), result, written)
    return 0


def screw_replay_result(law: ScrewLaw, run, codes, prediction, model_path: str) -> dict[str, Any]:
    residual = None if run.error is None else run.error - prediction
    scored = np.empty(0) if residual is None else residual[np.isfinite(residual)]
    metrics = {key: error_metrics(scored)[key] for key in ("rms_um", "max_um", "R_um")} if scored.size else {}
    samples = []
    for k in range(len(run.time)):
        sample = {
            "i": k + 1,
            "time_s": float(run.time[k]),
            "x_m": float(run.probe_x[k]),
            "code": int(codes[k]),
            "group": 1,
            "fault": int(codes[k]),
            "prediction_um": None if codes[k] else float(prediction[k]),
            "residual_um": None,
        }
        if residual is not None and not codes[k] and np.isfinite(residual[k]):
            sample["residual_um"] = float(residual[k])
        samples.append(sample)
    return {
        "model": model_path,
        "kind": "ballscrew",
        "run": run.source,
        "source": law.source,
        "alpha_law": law.law,
        "n_samples": len(run.time),
        "fault_samples": int(np.sum(codes != 0)),
        "samples": samples,
        "rms_um": metrics.get("rms_um"),
        "max_um": metrics.get("max_um"),
        "R_um": metrics.get("R_um"),
        "scored_samples": int(scored.size),
    }


def screw_replay_report(result: dict[str, Any]) -> str:
    lines = [
        f"run      {result['run']}: {result['n_samples']} samples, ball-screw law of source {result['source']} "
        f"(alpha {result['alpha_law']}), {result['fault_samples']} sample(s) with unusable readings"
    ]
    lines.append(common.residual_line(result))
    return "\n".join(lines)


def run_screw_export(args: argparse.Namespace) -> int:
    """``export --target c|json|all`` of one source's law; other targets refused with the reason."""
    common.plan_outputs(args, args.model, folder=args.out)
    targets = SCREW_TARGETS if args.target == "all" else (args.target,)
    for target in targets:
        check_screw_target(target)
    target_options(args, targets, {})
    law = screw_law(args)
    files: dict[str, str] = {}
    for target in targets:
        files.update(render_screw(law, target))
    common.write_exports(args, files)
    return 0


__all__ = ["run_screw_export", "run_screw_replay", "screw_law"]
