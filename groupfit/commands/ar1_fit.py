"""``groupfit fit --model ar1``: the AR(1) model fitted on a run and written as a model file (:mod:`groupfit.ar1`)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from groupfit import running
from groupfit.ar1.fitting import AR1Fit, closed_form_from_toml, decimate, decimation_step, fit_ar1_file
from groupfit.ar1.inputs import check_heat, check_heat_setting, refuse_heat_role
from groupfit.ar1.modelfile import MAX_HEAT_EXPONENT, STARTS
from groupfit.ar1.nextrun import expect_ar1, file_predictor
from groupfit.commands import common
from groupfit.data import load_run, numeric_column
from groupfit.errors import InputError
from groupfit.heldout.expect import NextRunExpectation
from groupfit.io import file_sha256
from groupfit.outputs import GROUPED_MODELS
from groupfit.plots import plot_fit

AR1_FITS = {"one-step": "one_step", "free-run": "free_run"}
GROUPED_ONLY = ("p", "select", "ridge", "position", "dead_band", "search", "criterion", "recalibrate")
DEFAULT_HEAT_EXPONENT = 5 / 3
"""C2 of an unseen heat level by (q/level)^X: bearing heat against speed."""
MIN_STEPS = 10
"""The fewest steps (rows at the model's step) ``fit --model ar1`` fits."""
FIT_TODO = "or model the run with the grouped model (leave out --model ar1)"
AR1_ONLY = ("heat", "period", "start", "ar1_fit", "heat_exponent", "closed_form")


def first_given(args: argparse.Namespace, names) -> str | None:
    """The option (``--heat-exponent``) of the first of ``names`` given on the command line; None when none is."""
    given = [name for name in names if getattr(args, name, None) not in (None, False)]
    return f"--{given[0].replace('_', '-')}" if given else None


def refuse_ar1_options(args: argparse.Namespace) -> None:
    """Refuse an option of ``--model ar1`` given to the grouped model's fit, which would ignore it."""
    option = first_given(args, AR1_ONLY)
    if option:
        raise InputError(
            f"{option} is an option of --model ar1, not of the grouped model; add --model ar1 or leave it out"
        )


def add_fit_options(parser: argparse.ArgumentParser) -> None:
    """The options of ``fit --model ar1``."""
    parser.add_argument(
        "--model",
        choices=("grouped", "ar1"),
        default="grouped",
        help="grouped regression (default), or the physics AR(1) model E(k) = C1 E(k-1) + C2(q_k)",
    )
    parser.add_argument("--heat", metavar="COLUMN", help="ar1: the heat column (speed, power or heat flux)")
    parser.add_argument(
        "--period",
        type=float,
        metavar="S",
        help="ar1: the step Δτ in s, a whole multiple of the run's period (default: the run's period)",
    )
    parser.add_argument(
        "--start",
        choices=STARTS,
        help="ar1: the free run starts from 0 (the paper's ΔL(0) = 0, default) or from the measured error",
    )
    parser.add_argument(
        "--ar1-fit",
        choices=tuple(AR1_FITS),
        help="ar1: least squares on the one-step equations (default) or on the free-run error",
    )
    parser.add_argument(
        "--heat-exponent",
        type=float,
        metavar="X",
        help="ar1: C2 of an unseen heat level by (q/level)^X (default 5/3, bearing heat against speed; 1 for a flux)",
    )
    parser.add_argument(
        "--closed-form",
        metavar="TOML",
        help="ar1: C1 and C2 from the rod's constants ([rod] table, e.g. configs/rod_ar1.toml; eq. 13-14) "
        "instead of the fit; the heat column is then a heat flux in W/m²",
    )


NO_ESTIMATE = (
    "no segment after the first 40 % of the run could be scored (the run before each has no heat level above "
    "0, or its fit would not settle); record a run with more changes of the heat column"
)


def with_expectation(result: AR1Fit, expectation: NextRunExpectation | None, path) -> None:
    """Record the expected next-run error in ``result``'s model file (``training``) and its scores, and the
    modelling file's SHA-256, so that ``replay`` of that file does not take it for a next run."""
    training = dict(result.model.training or {})
    training["recordings"] = [{"path": str(Path(path).resolve()), "sha256": file_sha256(path)}]
    if expectation is None:
        result.scores["expected_next_run_note"] = NO_ESTIMATE
    else:
        training.update(expectation.training())
        result.scores["expected_next_run_notes"] = list(expectation.notes)
    result.model = result.model.replace(training=training).checked()
    result.expectation = expectation


def run_fit(args: argparse.Namespace) -> int:
    """``groupfit fit --model ar1``: fit, write model.json and fit.png, print the summary."""
    option = first_given(args, GROUPED_ONLY)
    if option:
        raise InputError(f"{option} is an option of the grouped model, not of --model ar1")
    if not args.heat:
        raise InputError("--model ar1 needs --heat COLUMN: the heat input (spindle speed, power or heat flux)")
    args.start = args.start or "zero"
    args.ar1_fit = args.ar1_fit or "one-step"
    args.heat_exponent = DEFAULT_HEAT_EXPONENT if args.heat_exponent is None else args.heat_exponent
    if not (math.isfinite(args.heat_exponent) and 0.0 < args.heat_exponent <= MAX_HEAT_EXPONENT):
        raise InputError(f"--heat-exponent {args.heat_exponent:g}: give a number in (0, {MAX_HEAT_EXPONENT:g}]")
    config_path, settings = common.settings_with_data_options(args)
    data = settings.data
    out_dir = common.plan_outputs(
        args,
        config_path,
        data.path,
        args.closed_form,
        folder=args.out or settings.output_dir,
        files=("model.json", "fit.png"),
        json_model=GROUPED_MODELS,
    )
    if not data.paths:
        raise InputError("no data given: pass --data CSV or set [data] path in the configuration")
    if len(data.paths) > 1:
        raise InputError("--model ar1 takes one run (--data CSV)")
    clock = common.clock_options(args, data)
    run = load_run(data.paths[0], temps=[], time=data.time, error=data.error, error_limit=data.error_limit, **clock)
    common.print_notes([run], common.report_stream(args))
    refuse_heat_role(run, args.heat, FIT_TODO)
    heat = numeric_column(run.frame, args.heat, run.source, allow_nonfinite=False)
    check_heat(heat, source=str(run.source), name=args.heat)
    check_heat_setting(heat, source=str(run.source), name=args.heat, todo=FIT_TODO)
    step = decimation_step(run.period, args.period)
    heat, error = decimate(heat, step), decimate(run.error, step)
    if len(heat) < MIN_STEPS:
        raise InputError(
            f"{run.source}: --period {args.period:g} s leaves {len(heat)} step(s) of the run's {run.n_samples} rows; "
            f"the AR(1) model needs at least {MIN_STEPS}: choose a shorter step"
        )
    rod = closed_form_from_toml(args.closed_form) if args.closed_form else None
    options = dict(
        period_s=run.period * step,
        heat_name=args.heat,
        error_name=run.error_name,
        source=str(run.source),
        time_name=run.time_name,
        fit_method=AR1_FITS[args.ar1_fit],
        start=args.start,
        heat_exponent=args.heat_exponent,
        rod=rod,
    )
    result = fit_ar1_file(heat, error, **options)
    result.scores["decimation"] = step
    with running.stage("next-run estimate", enabled=not args.quiet):
        predict = file_predictor(heat, error, lambda q, e: fit_ar1_file(q, e, **options).model)
        expectation = expect_ar1(heat, error, predict, heat_name=args.heat)
    with_expectation(result, expectation, data.paths[0])
    model_path, figure_path = out_dir / "model.json", out_dir / "fit.png"
    result.model.save(model_path)
    plot_fit(
        decimate(run.time, step),
        result.error,
        result.prediction,
        [],
        [(1, len(result.error))],
        figure_path,
        title=f"{run.name}: AR(1), C1 = {result.model.c1:.5f}, start {args.start}",
        label="AR(1) free run",
    )
    json_path = common.write_json(args.json, result.to_json())
    common.commit_outputs()
    print(
        result.summary() + "\nwrote   " + common.wrote_line([model_path, figure_path, json_path]),
        file=common.report_stream(args),
    )
    return 0
