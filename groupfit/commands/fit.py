"""``groupfit fit``: optimise the hard breaks, fit the soft groups, save the model."""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from groupfit.commands import ar1_fit as ar1_commands
from groupfit.commands import fit_mlr
from groupfit.commands.common import (
    StageProgress,
    add_budget_option,
    add_json_option,
    add_out_option,
    add_quiet_option,
    add_reference_option,
    add_run_options,
    check_exact_budget,
    check_output_dir,
    commit_outputs,
    config_with_data_options,
    configured_clock,
    configured_reference,
    load_configured_runs,
    plan_outputs,
    print_notes,
    report_stream,
    ridge_value,
    seed_value,
    write_json,
    wrote_line,
)
from groupfit.commands.recalibrate_option import add_recalibrate_option, recalibrated
from groupfit.config import override
from groupfit.data import ERROR_LIMIT_UM, TEMP_RANGE_C, Run, join_runs, measured_rows
from groupfit.errors import InputError
from groupfit.fitting import FitResult
from groupfit.heldout.check import held_out_check, ridge_setting, select_inputs
from groupfit.heldout.expect import NextRunExpectation, expect_next_run
from groupfit.heldout.nextrun import next_run_splits
from groupfit.heldout.selection import SELECTION_METHODS
from groupfit.heldout.span import SPAN_KEY, input_span
from groupfit.inference.cli import add_interval_options, check_block, intervals_from_args
from groupfit.model import DeadBand
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.select_p import choose_p, exact_path
from groupfit.plots import plot_fit
from groupfit.position import choose_p0, cross_validate_order, load_position_run, residual_by_order, with_position
from groupfit.position_plot import plot_position
from groupfit.reference import START, with_reference

NEXT_RUN = "next-run"
P_RULES = (NEXT_RUN, "bic", "target")


def add_parser(verbs) -> None:
    fit = verbs.add_parser("fit")
    add_run_options(fit)
    fit.add_argument(
        "--p",
        type=whole_or_auto("p"),
        help="number of hard break points; default (or 'auto'): chosen by --choose over 0…pmax",
    )
    fit.add_argument("--pmax", type=int, help="largest p tried when p is chosen (default 3)")
    fit.add_argument(
        "--choose",
        "--p-rule",
        dest="p_rule",
        choices=P_RULES,
        help="how p is chosen: next-run (default: the least expected next-run error, one-standard-error rule "
        "toward fewer breaks), bic (in sample), target (fewest breaks with R <= --p-target)",
    )
    fit.add_argument("--p-target", metavar="R", help="target R for --p-rule target: µm, or a percentage like 20%%")
    fit.add_argument("--n", type=int, help="soft offset: samples shared by neighbouring groups")
    fit.add_argument("--c", type=float, help="spacing coefficient: groups hold more than c·M samples")
    fit.add_argument("--objective", choices=("sae", "sse"), help="residual sum to minimise")
    fit.add_argument("--no-intercept", action="store_true", help="fit groups without a constant term")
    fit.add_argument("--search", choices=("ga", "exact"), help="genetic algorithm or exact dynamic programming")
    fit.add_argument("--seed", type=seed_value, help="seed of the genetic algorithm")
    fit.add_argument(
        "--certify",
        choices=("auto", "yes", "no"),
        help="GA: also run the exact search and print the gap (auto: when cheap; the default)",
    )
    fit.add_argument("--criterion", metavar="COLUMN", help="switching criterion sensor (default: the most active)")
    add_reference_option(fit)
    fit.add_argument(
        "--select",
        choices=SELECTION_METHODS,
        help="choose the inputs among --temps on held-out conditions (forward, lasso or cluster)",
    )
    fit.add_argument("--sensors", type=int, metavar="K", help="with --select: how many inputs (default: chosen)")
    fit.add_argument(
        "--ridge",
        type=ridge_value,
        metavar="ALPHA|auto",
        help="shrink the coefficients of a global model (p = 0) on many collinear inputs by a ridge penalty; "
        "auto: the penalty with the least error on held-out conditions or runs",
    )
    fit.add_argument(
        "--position",
        metavar="COLUMN",
        help="axis position column (mm) of a run measured at several positions (long table; a wide one has "
        "err_P<mm> columns): fit E(P, T) = K0(T) + c1(T)(P - P0) + ...",
    )
    fit.add_argument(
        "--position-order",
        type=whole_or_auto("order"),
        metavar="N|auto",
        help="with --position: polynomial order in P (default 1: K0 + tanb (P - P0)); auto: chosen by "
        "cross-validation over held-out positions",
    )
    fit.add_argument(
        "--position-ref",
        metavar="MM|middle|min|max",
        help="with --position: the reference position P0 (default: the middle of the measured travel)",
    )
    fit.add_argument(
        "--dead-band",
        type=float,
        metavar="C",
        help="no update of the compensation while every input is within C degC of --dead-band-ref",
    )
    fit.add_argument(
        "--dead-band-ref",
        metavar="COLUMN",
        help="reference sensor of --dead-band (default: the --reference column)",
    )
    add_json_option(fit)
    add_out_option(fit, "folder for model.json and fit.png")
    add_quiet_option(fit)
    add_budget_option(fit)
    add_interval_options(fit)
    add_recalibrate_option(fit)
    ar1_commands.add_fit_options(fit)
    fit_mlr.add_options(fit)
    fit.set_defaults(handler=run_fit)


FIT_FILES = ("model.json", "fit.png", "position.png")
"""What fit writes into --out (position.png for a position model)."""


def run_fit(args: argparse.Namespace) -> int:
    if args.model == "ar1":
        return ar1_commands.run_fit(args)
    config_path, config = config_with_data_options(args)
    override(config, "model", "p", args.p)
    override(config, "model", "pmax", args.pmax)
    override(config, "model", "p_rule", args.p_rule)
    override(config, "model", "p_target", args.p_target)
    override(config, "model", "n", args.n)
    override(config, "model", "c", args.c)
    override(config, "model", "objective", args.objective)
    if args.no_intercept:
        config["model"]["intercept"] = False
    override(config, "model", "criterion", args.criterion)
    override(config, "search", "method", args.search)
    override(config, "search", "seed", args.seed)
    override(config, "search", "certify", {"yes": True, "no": False}.get(args.certify, args.certify))
    override(config, "output", "dir", args.out)
    plan_outputs(args, config_path, config["data"].get("path"), folder=config["output"]["dir"], files=FIT_FILES)

    paths = config["data"].get("path")
    position_run = None
    check_position_options(args)
    if args.position:
        position_run = load_position_data(config, args.position)
        runs = [position_run.run]
    else:
        runs = load_configured_runs(config, missing_error=True)
    print_notes(runs, report_stream(args))
    if config["model"]["p"] == "auto" and (len(runs) > 1 or position_run is not None):
        config["model"]["p"] = 0  # several runs, or check runs at positions: a global model
    if len(runs) > 1 and config["model"]["p"] != 0:
        split = "" if isinstance(paths, (list, tuple)) else " (--resample split the log at its gaps)"
        raise InputError(
            f"{len(runs)} runs given{split}: several runs fit a global model, --p 0; a grouped model's "
            "breaks belong to one run (fit it per run and operating condition)"
        )
    run = join_runs(runs)
    reference = configured_reference(args, config, run)
    if len(runs) > 1 and reference == START:
        runs = [with_reference(r, START) for r in runs]  # each run's own start
        run = join_runs(runs)
    else:
        run = with_reference(run, reference)
    if config["model"]["p"] == "auto" and np.isnan(run.error).any():
        config["model"]["p"] = 0  # an error not on every row: a global model on the measured rows
    check_measured(run, config["model"]["p"])
    check_block(args, run.n_samples)
    input_selection = None
    if position_run is not None:
        position_run = replace(position_run, run=run)
        if args.select:
            raise InputError("--select is not available with --position; name the inputs with --temps")
        if args.ridge is not None:
            raise InputError("--ridge is not available with --position: the position terms are fitted by least squares")
    estimate_runs = [measured_rows(with_reference(r, reference)) for r in runs] if position_run is None else []
    if args.select:
        run, input_selection = select_run_inputs(run, [r.frame for r in runs], args.select, args.sensors, estimate_runs)
        estimate_runs = [with_inputs(r, run.temp_names) for r in estimate_runs]
    elif args.sensors is not None:
        raise InputError("--sensors K needs --select forward|lasso|cluster")
    if args.backward is not None:
        if args.select or position_run is not None:
            raise InputError("--backward chooses the inputs itself: not with --select or --position")
        intercept = config["model"]["intercept"]
        if config["model"]["p"] == "auto":
            config["model"]["p"] = 0  # backward elimination is for a global regression
        run, input_selection = fit_mlr.backward_run(run, args.backward, p=config["model"]["p"], fit_intercept=intercept)
        estimate_runs = [with_inputs(r, run.temp_names) for r in estimate_runs]
    criterion = config["model"].get("criterion")
    if criterion is not None and criterion not in run.temp_names:
        raise InputError(
            f"switching criterion '{criterion}' is not a model input; choose one of {', '.join(run.temp_names)}"
        )
    n_coef = run.temps.shape[1] + int(config["model"]["intercept"])
    if config["model"]["p"] == "auto" and config["model"]["p_rule"] != NEXT_RUN:
        check_exact_budget(
            args, run, n_coef, config["model"]["objective"], max(config["model"]["pmax"], 0), "--p auto's exact path"
        )
    elif config["search"]["method"] == "exact" and isinstance(config["model"]["p"], int):
        check_exact_budget(args, run, n_coef, config["model"]["objective"], config["model"]["p"], "the exact search")
    selection = expectation = None
    if config["model"]["p"] == "auto" and config["model"]["pmax"] < 0:
        raise InputError(f"--pmax {config['model']['pmax']}: the largest p tried must be 0 or more")
    if config["model"]["p"] == "auto" and config["model"]["p_rule"] == NEXT_RUN:
        p_values = (0,) if args.ridge is not None else tuple(range(config["model"]["pmax"] + 1))
        expectation = model_expectation(config, estimate_runs, p_values)
        config["model"]["p"] = expectation.candidates[expectation.chosen]
    elif config["model"]["p"] == "auto":
        selection = select_breaks(config, run)
        config["model"]["p"] = selection["p"]
    elif not isinstance(config["model"]["p"], int):
        raise InputError(f"p = {config['model']['p']!r}: give a whole number or 'auto'")
    estimator = GroupedRegressor.from_config(config)
    frames = [r.frame for r in runs]
    not_conditions = {run.time_name, run.error_name, *run.temp_names}  # the held-out folds come from the others
    ridge = None
    if args.ridge is not None:
        settings = config["model"]
        splits = next_run_splits(estimate_runs)
        ridge = ridge_setting(
            args.ridge,
            settings["p"],
            run.temps,
            run.error,
            frames,
            not_conditions,
            settings["intercept"],
            splits=splits,
            splits_name=f"{len(splits)} folds that imitate a next run",
        )
        estimator.set_params(ridge_alpha=ridge.alpha)
    out_dir = check_output_dir(config["output"]["dir"])
    progress = StageProgress(enabled=not args.quiet)
    fit_run = measured_rows(run)
    try:
        estimator.fit(fit_run.temps, fit_run.error, progress=progress)
        seed = config["search"]["seed"]
        intervals = intervals_from_args(args, estimator, fit_run.temps, fit_run.error, seed, progress)
    finally:
        progress.close()
    model = estimator.to_model_file(run, criterion)  # the valid ranges over every row, measured or not
    position_note = ""
    if position_run is None and (expectation is None or ridge is not None):
        alpha = ridge.alpha if ridge is not None else 0.0
        try:
            expectation = model_expectation(config, estimate_runs, (config["model"]["p"],), alpha)
        except InputError as exc:
            position_note += f"\nnote    no next-run estimate: {exc}"
    training = {**model.training, SPAN_KEY: input_span(run.temp_names, run.temps)}
    if expectation is not None:
        training.update(expectation_training(expectation, config))
    model = model.replace(training=training)
    if position_run is not None:
        model, position_note = position_model(args, model, position_run)
    if fit_run is not run:
        position_note += (
            f"\nnote    the error is measured on {fit_run.n_samples} of {run.n_samples} rows: the model is fitted "
            "on those"
        )
    held_out = None
    if position_run is None:
        alpha = ridge.alpha if ridge is not None else 0.0
        intercept = config["model"]["intercept"]
        grouped = model.to_dict() if estimator.p > 0 else None
        held_out = held_out_check(run.temps, run.error, frames, not_conditions, intercept, alpha, grouped)
        model, recal_note = recalibrated(model, [(r.frame, r.error) for r in runs], args.recalibrate)
        position_note = recal_note + position_note
    result = FitResult(
        estimator, fit_run, model, selection, input_selection, intervals, ridge, held_out, expectation=expectation
    )
    if estimator.p == 0 and ridge is None and position_run is None:
        result.statistics = fit_mlr.statistics(fit_run, fit_intercept=config["model"]["intercept"])
    run = fit_run

    model_path = out_dir / "model.json"
    figure_path = out_dir / "fit.png"
    result.model.save(model_path)
    plot_fit(
        run.time,
        run.error,
        run.error - estimator.residuals_,
        estimator.breaks_,
        estimator.soft_groups_,
        figure_path,
        title=f"{run.name}: grouped model, p = {len(estimator.breaks_)}, "
        f"{estimator.objective} Rg = {estimator.objective_value_:.4g}",
        break_intervals=intervals.intervals,
    )
    position_figure = None
    if position_run is not None:
        position_figure = out_dir / "position.png"
        plot_position(result.model, position_run, position_figure)
    json_path = write_json(args.json, result.to_json())
    commit_outputs()
    written = wrote_line([model_path, figure_path, position_figure, json_path])
    print(result.summary() + position_note + "\nwrote   " + written, file=report_stream(args))
    return 0


def model_expectation(config: dict, runs: list[Run], p_values, ridge_alpha: float = 0.0) -> NextRunExpectation:
    """The expected next-run error of the candidates ``p_values`` (:mod:`groupfit.heldout.expect`)."""
    model = config["model"]
    try:
        result = expect_next_run(
            runs, p_values, n=model["n"], c=float(model["c"]), fit_intercept=model["intercept"], ridge_alpha=ridge_alpha
        )
    except ValueError as exc:
        raise InputError(f"{runs[0].source}: the next-run estimate: {exc}; give --p or record a longer run") from None
    return result


def expectation_training(expectation: NextRunExpectation, config: dict) -> dict:
    """The model file's ``training`` keys of the next-run expectation and of how p was chosen."""
    data = expectation.to_json()
    chosen = config["model"]["p"] if len(expectation.candidates) == 1 else data["chosen"]["p"]
    return {
        **expectation.training(),
        "model_choice": {
            "p": chosen,
            "rule": data["chosen"]["rule"] if len(expectation.candidates) > 1 else "given",
            "candidates": data["candidates"],
            "notes": data["notes"],
        },
    }


def with_inputs(run: Run, names) -> Run:
    """The run restricted to the inputs ``names``."""
    keep = [run.temp_names.index(name) for name in names]
    return replace(run, temps=run.temps[:, keep], temp_names=tuple(names))


def whole_or_auto(what: str):
    """The argparse type of an option taking a whole number or 'auto' (``what`` names it in the message)."""

    def value(text: str) -> int | str:
        if text == "auto":
            return text
        try:
            return int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid {what}: {text!r} (a whole number or 'auto')") from None

    return value


def check_measured(run: Run, p) -> None:
    """Rows without a measured error are for a global model only (a grouped model's breaks are row indices)."""
    missing = int(np.isnan(run.error).sum())
    if missing and p != 0:
        row = int(np.flatnonzero(np.isnan(run.error))[0]) + 1
        raise InputError(
            f"{run.source}: row {row}, column '{run.error_name}' is empty ({missing} rows without a measured "
            f"error); a grouped model (p = {p}) needs the error on every row: fill or drop those rows, or fit a "
            "global model (--p 0) on the measured rows"
        )


def check_position_options(args: argparse.Namespace) -> None:
    """The position and dead-band options that need another one."""
    if not args.position:
        for name in ("position_order", "position_ref"):
            if getattr(args, name) is not None:
                raise InputError(f"--{name.replace('_', '-')} needs --position COLUMN")
    if args.dead_band_ref is not None and args.dead_band is None:
        raise InputError("--dead-band-ref needs --dead-band C")
    if args.dead_band is not None and not (0 < args.dead_band <= 50):
        raise InputError(f"--dead-band {args.dead_band:g}: a threshold in (0, 50] degC")


def load_position_data(config: dict, column: str):
    """The run of ``--position COLUMN`` (long or wide table; :func:`groupfit.position.load_position_run`)."""
    data = config["data"]
    path = data.get("path")
    if not path:
        raise InputError("no data given: pass --data CSV or set [data] path in the configuration")
    if isinstance(path, (list, tuple)):
        raise InputError("--position takes one run (a long or wide table of check runs)")
    limits = {
        "temp_range": data.get("temp_range", TEMP_RANGE_C),
        "error_limit": data.get("error_limit", ERROR_LIMIT_UM),
    }
    clock = configured_clock(config)
    columns = {"temps": data.get("temps"), "time": data["time"], "error": data["error"]}
    return load_position_run(path, column, **columns, **limits, **clock)


def position_model(args: argparse.Namespace, model, position_run) -> tuple:
    """The model with its position terms (and dead band), and the report's lines on them."""
    p0 = choose_p0(position_run, args.position_ref)
    order = args.position_order if args.position_order is not None else 1
    lines = []
    if order == "auto":
        chosen = cross_validate_order(position_run, p0=p0, intercept=model.intercept)
        order = chosen["order"]
        scores = ", ".join(f"{k}: {v:.3g}" for k, v in zip(chosen["orders"], chosen["rms_um"]))
        lines.append(f"position order {order} by cross-validation over held-out positions (RMS um: {scores})")
    dead_band = None
    if args.dead_band is not None:
        reference = args.dead_band_ref or (model.reference if model.reference not in (None, "start") else None)
        if reference is None:
            raise InputError("--dead-band needs its reference sensor: --dead-band-ref COLUMN (or --reference COLUMN)")
        if reference not in position_run.run.frame.columns:
            raise InputError(f"--dead-band-ref '{reference}': no such column in the run")
        dead_band = DeadBand(reference=reference, threshold_c=float(args.dead_band))
    fitted = with_position(model, position_run, order, p0, dead_band=dead_band)
    orders = residual_by_order(model, position_run, p0)
    fitted = fitted.replace(training={**(fitted.training or {}), "position_orders": orders})
    training = fitted.training
    lines.append(
        f"position {position_run.column}: order {order}, P0 = {p0:g} mm, travel {position_run.travel[0]:g} .. "
        f"{position_run.travel[1]:g} mm, {len(position_run.positions)} positions x {position_run.run.n_samples} "
        f"check runs; residual RMS {training['position_rms_um']:.3g} um, max {training['position_max_um']:.3g} um"
    )
    lines.append("residual by order (max / mean |e| um): " + order_table_text(orders))
    return fitted, "\n" + "\n".join(lines)


def order_table_text(orders: list[dict]) -> str:
    """The per-order residual table in one line: ``1: 0.53 / 0.19, 2: …``."""
    return ", ".join(f"{row['order']}: {row['max_um']:.3g} / {row['mean_um']:.3g}" for row in orders)


def select_run_inputs(run: Run, frames: list, method: str, k: int | None, runs: list[Run]) -> tuple[Run, dict]:
    """The run restricted to the inputs ``method`` chooses, scored on folds that imitate a next run.

    ``runs``: the runs (measured rows, reference applied) the folds are cut from
    (:func:`groupfit.heldout.nextrun.next_run_splits`).
    """
    if k is not None and not 1 <= k <= len(run.temp_names):
        raise InputError(f"--sensors {k}: choose 1 to {len(run.temp_names)} of the {len(run.temp_names)} inputs")
    exclude = {run.time_name, run.error_name, *run.temp_names}
    splits = next_run_splits(runs)
    names, _ = select_inputs(run.temps, run.error, run.temp_names, frames, exclude, method, k, splits=splits)
    folds = f"{len(splits)} folds that imitate a next run (forward chaining or leave-one-run-out)"
    return with_inputs(run, names), {
        "method": method,
        "inputs": names,
        "candidates": len(run.temp_names),
        "folds": folds,
    }


def select_breaks(config: dict, run: Run) -> dict:
    """Choose p over 0…pmax from the certified optimum of every p."""
    model = config["model"]
    path = exact_path(
        run.temps,
        run.error,
        model["pmax"],
        n=model["n"],
        c=float(model["c"]),
        objective=model["objective"],
        fit_intercept=model["intercept"],
    )
    n_coef = run.temps.shape[1] + int(model["intercept"])
    selection = choose_p(path["rss"], path["R"], run.n_samples, n_coef, model["p_rule"], model.get("p_target"))
    if selection["p"] is None:
        raise InputError(
            f"no p up to {len(path['R']) - 1} meets the target R = {selection['target_um']:g} µm "
            f"(best: {min(path['R']):.4g} µm); raise --p-target or --pmax"
        )
    selection["R_um"] = path["R"]
    selection["breaks"] = path["breaks"]
    return selection


__all__ = ["run_fit", "select_breaks"]
