"""``groupfit fit``: optimise the hard breaks, fit the soft groups, save the model."""

from __future__ import annotations

import argparse

from groupfit.commands.common import (
    StageProgress,
    add_budget_option,
    add_json_option,
    add_out_option,
    add_quiet_option,
    add_reference_option,
    add_run_options,
    check_exact_budget,
    check_json_target,
    check_output_dir,
    config_with_data_options,
    configured_reference,
    load_configured_run,
    report_stream,
    write_json,
    wrote_line,
)
from groupfit.config import default_config_path, override
from groupfit.data import Run, join_runs
from groupfit.errors import InputError
from groupfit.fitting import FitResult
from groupfit.inference.cli import add_interval_options, intervals_from_args
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.select_p import choose_p, exact_path
from groupfit.reference import START, with_reference
from groupfit.sweep.selection import SELECTION_METHODS


def add_parser(verbs) -> None:
    fit = verbs.add_parser("fit")
    add_run_options(fit)
    fit.add_argument("--p", type=p_value, help="number of hard break points, or 'auto'")
    fit.add_argument("--pmax", type=int, help="largest p tried by --p auto (default 6)")
    fit.add_argument("--p-rule", choices=("bic", "target"), help="how --p auto chooses (default bic)")
    fit.add_argument("--p-target", metavar="R", help="target R for --p-rule target: µm, or a percentage like 20%%")
    fit.add_argument("--n", type=int, help="soft offset: samples shared by neighbouring groups")
    fit.add_argument("--c", type=float, help="spacing coefficient: groups hold more than c·M samples")
    fit.add_argument("--objective", choices=("sae", "sse"), help="residual sum to minimise")
    fit.add_argument("--no-intercept", action="store_true", help="fit groups without a constant term")
    fit.add_argument("--search", choices=("ga", "exact"), help="genetic algorithm or exact dynamic programming")
    fit.add_argument("--seed", type=int, help="seed of the genetic algorithm")
    fit.add_argument("--criterion", metavar="COLUMN", help="switching criterion sensor (default: the most active)")
    add_reference_option(fit)
    fit.add_argument(
        "--select",
        choices=SELECTION_METHODS,
        help="choose the inputs among --temps on held-out conditions (forward, lasso or cluster)",
    )
    fit.add_argument("--sensors", type=int, metavar="K", help="with --select: how many inputs (default: chosen)")
    add_json_option(fit)
    add_out_option(fit, "folder for model.json and fit.png")
    add_quiet_option(fit)
    add_budget_option(fit)
    add_interval_options(fit)
    fit.set_defaults(handler=run_fit)


def run_fit(args: argparse.Namespace) -> int:
    config = config_with_data_options(args, args.config or default_config_path())
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
    override(config, "output", "dir", args.out)
    check_json_target(args)
    check_output_dir(config["output"]["dir"])

    paths = config["data"].get("path")
    runs = (
        [load_configured_run(config, p) for p in paths]
        if isinstance(paths, (list, tuple))
        else [load_configured_run(config)]
    )
    if len(runs) > 1 and config["model"]["p"] != 0:
        raise InputError(
            f"{len(runs)} runs given: several runs fit a global model, --p 0; a grouped model's "
            "breaks belong to one run (fit it per run and operating condition)"
        )
    run = join_runs(runs)
    if len(runs) > 1 and configured_reference(args, config, run) == START:
        runs = [with_reference(r, START) for r in runs]  # each run's own start
        run = join_runs(runs)
    else:
        run = with_reference(run, configured_reference(args, config, run))
    input_selection = None
    if args.select:
        run, input_selection = select_run_inputs(run, [r.frame for r in runs], args.select, args.sensors)
    elif args.sensors is not None:
        raise InputError("--sensors K needs --select forward|lasso|cluster")
    criterion = config["model"].get("criterion")
    if criterion is not None and criterion not in run.temp_names:
        raise InputError(
            f"switching criterion '{criterion}' is not a model input; choose one of {', '.join(run.temp_names)}"
        )
    n_coef = run.temps.shape[1] + int(config["model"]["intercept"])
    if config["model"]["p"] == "auto":
        check_exact_budget(
            args, run, n_coef, config["model"]["objective"], max(config["model"]["pmax"], 0), "--p auto's exact path"
        )
    elif config["search"]["method"] == "exact" and isinstance(config["model"]["p"], int):
        check_exact_budget(args, run, n_coef, config["model"]["objective"], config["model"]["p"], "the exact search")
    selection = None
    if config["model"]["p"] == "auto" and config["model"]["pmax"] < 0:
        raise InputError(f"--pmax {config['model']['pmax']}: the largest p tried must be 0 or more")
    if config["model"]["p"] == "auto":
        selection = select_breaks(config, run)
        config["model"]["p"] = selection["p"]
    elif not isinstance(config["model"]["p"], int):
        raise InputError(f"p = {config['model']['p']!r}: give a whole number or 'auto'")
    estimator = GroupedRegressor.from_config(config)
    out_dir = check_output_dir(config["output"]["dir"])
    progress = StageProgress(enabled=not args.quiet)
    try:
        estimator.fit(run.temps, run.error, progress=progress)
        intervals = intervals_from_args(args, estimator, run.temps, run.error, config["search"]["seed"], progress)
    finally:
        progress.close()
    result = FitResult(estimator, run, estimator.to_model_file(run, criterion), selection, input_selection, intervals)

    from groupfit.plots import plot_fit

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
    json_path = write_json(args.json, result.to_json())
    written = wrote_line([model_path, figure_path, json_path])
    print(result.summary() + "\nwrote   " + written, file=report_stream(args))
    return 0


def select_run_inputs(run: Run, frames: list, method: str, k: int | None) -> tuple[Run, dict]:
    """The run restricted to the inputs ``method`` chooses, scored on held-out conditions or runs."""
    from dataclasses import replace

    from groupfit.diagnose.candidates import usable_columns
    from groupfit.diagnose.folds import make_folds
    from groupfit.sweep.selection import select_sensors

    if k is not None and not 1 <= k <= len(run.temp_names):
        raise InputError(f"--sensors {k}: choose 1 to {len(run.temp_names)} of the {len(run.temp_names)} inputs")
    columns, _ = usable_columns(run.frame, {run.time_name, run.error_name, *run.temp_names})
    folds = make_folds(frames, columns)
    names = select_sensors(run.temps, run.error, run.temp_names, method, k, splits=folds.index_splits())
    keep = [run.temp_names.index(name) for name in names]
    selected = replace(run, temps=run.temps[:, keep], temp_names=tuple(names))
    return selected, {"method": method, "inputs": names, "candidates": len(run.temp_names), "folds": folds.describe()}


def p_value(text: str) -> int | str:
    """--p: a whole number or 'auto'."""
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid p: {text!r} (a whole number or 'auto')") from None


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
