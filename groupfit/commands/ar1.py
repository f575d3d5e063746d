"""The AR(1) model on the command line (:mod:`groupfit.ar1`): ``replay`` and ``export``.

``fit --model ar1`` is :mod:`groupfit.commands.ar1_fit`.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from groupfit.ar1.export import render
from groupfit.ar1.modelfile import AR1File
from groupfit.ar1.rule import FAULT_HEAT, AR1Rule
from groupfit.ar1.sampling import decimate, decimation_step
from groupfit.commands import common
from groupfit.commands.export_options import AR1_TARGET_OPTIONS, target_options
from groupfit.commands.replay_expectation import expectation_check, expectation_line
from groupfit.data import load_run, numeric_column, without_implausible_errors
from groupfit.errors import InputError
from groupfit.metrics import error_metrics, prediction_accuracy
from groupfit.plots import plot_fit


def run_replay(args: argparse.Namespace) -> int:
    """``groupfit replay`` of an AR(1) model file: the routine over a recorded run, every Δτ."""
    out_dir = common.plan_outputs(args, args.model, args.data, folder=args.out, files=("replay.png",))
    model = AR1File.load(args.model)
    error = args.error or model.error or "error_um"
    time = args.time or (model.training or {}).get("time") or "time_s"
    run = load_run(
        args.data,
        temps=[],
        time=time,
        error=error,
        require_error=False,
        allow_nonfinite=True,
        error_limit=None,
        **common.clock_options(args),
    )
    run = without_implausible_errors(run, common.range_options(args)["error_limit"])
    common.print_notes([run], common.report_stream(args))
    try:
        step = decimation_step(run.period, model.sampling_period_s, what="the model's step")
    except InputError as exc:
        raise InputError(f"{run.source}: {exc}") from None
    heat = decimate(numeric_column(run.frame, model.heat, run.source, allow_nonfinite=True), step)
    measured = decimate(run.error, step) if run.error is not None else None
    if measured is not None and not np.isfinite(measured).any():
        measured = None
    if model.start == "measured":
        if measured is None or not np.isfinite(measured[0]):
            raise InputError(
                f"{run.source}: the model starts from the measured error: column '{error}' row 1 is needed"
            )
        initial = float(measured[0])
    else:
        initial = 0.0
    result = AR1Rule(model, precision=args.precision).replay(heat, initial_um=initial)
    out = {
        "model": str(args.model),
        "kind": "ar1",
        "run": str(run.source),
        "decimation": step,
        "start": model.start,
        "initial_um": initial,
        "precision": args.precision,
        "time_s": decimate(run.time, step).tolist(),
        "prediction_um": result.prediction_um.tolist(),
        "fault": result.fault.tolist(),
    }
    lines = [
        f"replay  {run.source}: AR(1) every {model.sampling_period_s:g} s ({len(heat)} steps, every {step} row(s)), "
        f"start {model.start} (E0 = {initial:g} µm), {args.precision} precision",
        f"faults  {int(np.sum(result.fault == FAULT_HEAT))} held heat reading(s)",
    ]
    out["samples"] = ar1_samples(out["time_s"], result, measured)
    out["rms_um"] = None
    if measured is not None:
        scored = np.isfinite(measured)
        residual = measured[scored] - result.prediction_um[scored]
        scores = {**error_metrics(residual), "accuracy_percent": prediction_accuracy(measured[scored], residual)}
        out["scores"] = {**scores, "scored_samples": int(scored.sum())}
        out["rms_um"] = scores["rms_um"]
        lines.append(
            f"error   RMS {scores['rms_um']:.4g} µm, max {scores['max_um']:.4g} µm, prediction accuracy "
            f"{scores['accuracy_percent']:.1f} % over {int(scored.sum())} measured step(s)"
        )
    else:
        lines.append("error   none (the run has no measured error: no error column, or no reading within its range)")
    out.update(expectation_check(model.training, out, args.data))
    if "expected_next_run" in out:
        lines.append(expectation_line(out["expected_next_run"]))
    figures = []
    if out_dir is not None and measured is not None:
        figure = out_dir / "replay.png"
        time_s = decimate(run.time, step)
        title = f"{run.name}: AR(1) routine, start {model.start}"
        plot_fit(time_s, measured, result.prediction_um, [], [(1, len(heat))], figure, title=title, label="AR(1)")
        figures.append(figure)
    common.finish_outputs(args, "\n".join(lines), out, figures)
    return 0


def ar1_samples(time_s: list, result, measured: np.ndarray | None) -> list[dict]:
    """The routine's steps as ``replay --json`` gives a grouped model's samples (one group)."""
    samples = []
    for k, prediction in enumerate(result.prediction_um):
        residual = None if measured is None else measured[k] - prediction
        samples.append(
            {
                "i": k + 1,
                "time_s": float(time_s[k]),
                "group": 1,
                "prediction_um": float(prediction),
                "fault": int(result.fault[k]),
                "residual_um": float(residual) if residual is not None and np.isfinite(residual) else None,
            }
        )
    return samples


def run_export(args: argparse.Namespace) -> int:
    """``groupfit export`` of an AR(1) model file: C, ST, JSON and the controller sheet."""
    model = AR1File.load(args.model)
    if getattr(args, "period", None) is not None and not math.isclose(args.period, model.sampling_period_s):
        raise InputError(
            f"{args.model}: an AR(1) model steps every {model.sampling_period_s:g} s (its C1 and C2 belong to that "
            f"step): call it at that period, or refit with fit --model ar1 --period {args.period:g}"
        )
    common.plan_outputs(args, args.model, folder=args.out)
    targets = ("c", "st", "json", "sheet") if args.target == "all" else (args.target,)
    options = target_options(args, targets, AR1_TARGET_OPTIONS)
    files: dict[str, str] = {}
    for target in targets:
        files.update(render(model, target, **options))
    common.write_exports(args, files)
    return 0


__all__ = ["run_export", "run_replay"]
