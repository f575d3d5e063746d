"""``groupfit fit``: optimise the hard breaks, fit the soft groups, save the model."""

from __future__ import annotations

import argparse
from pathlib import Path

from groupfit.commands.common import (
    StageProgress,
    add_data_options,
    check_output_dir,
    config_with_data_options,
    load_configured_run,
    report_stream,
    write_json,
)
from groupfit.config import default_config_path, ga_settings, override
from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.grouping import served_ranges
from groupfit.inference.cli import add_interval_options, intervals_from_args
from groupfit.modelfile import model_to_dict, save_model
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.select_p import choose_p, exact_path


def add_parser(verbs) -> None:
    fit = verbs.add_parser("fit", help="optimise hard breaks, fit soft-group coefficients, save the model")
    fit.add_argument("config", nargs="?", metavar="CONFIG", help="TOML run configuration")
    add_data_options(fit)
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
    fit.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' for stdout)")
    fit.add_argument("--out", metavar="DIR", help="folder for model.json and fit.png")
    fit.add_argument("--quiet", action="store_true", help="no progress bar")
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

    run = load_configured_run(config)
    criterion = config["model"].get("criterion")
    if criterion is not None and criterion not in run.temp_names:
        raise InputError(
            f"switching criterion '{criterion}' is not a model input; choose one of {', '.join(run.temp_names)}"
        )
    selection = None
    if config["model"]["p"] == "auto":
        selection = select_breaks(config, run)
        config["model"]["p"] = selection["p"]
    elif not isinstance(config["model"]["p"], int):
        raise InputError(f"p = {config['model']['p']!r}: give a whole number or 'auto'")
    estimator = estimator_from_config(config)
    out_dir = check_output_dir(config["output"]["dir"])
    progress = StageProgress(enabled=not args.quiet)
    try:
        estimator.fit(run.temps, run.error, progress=progress)
        intervals = intervals_from_args(args, estimator, run.temps, run.error, config["search"]["seed"], progress)
    finally:
        progress.close()
    model = model_to_dict(estimator, run, criterion)

    from groupfit.plots import plot_fit

    model_path = out_dir / "model.json"
    figure_path = out_dir / "fit.png"
    save_model(model, model_path)
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
    result = {**model, "search": estimator.search_, "break_intervals": intervals.to_json()}
    if selection is not None:
        result["p_selection"] = selection
    write_json(args.json, result)
    report = fit_report(estimator, run, model, [model_path, figure_path], intervals)
    if selection is not None:
        report = selection_summary(selection) + "\n" + report
    print(report, file=report_stream(args))
    return 0


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


def selection_summary(selection: dict) -> str:
    table = ", ".join(
        f"p={p}: R {r:.4g} µm, BIC {b:.1f}" for p, (r, b) in enumerate(zip(selection["R_um"], selection["bic"]))
    )
    rule = "smallest BIC" if selection["rule"] == "bic" else f"fewest breaks with R <= {selection['target_um']:.4g} µm"
    return f"p auto  {rule}: p = {selection['p']}  ({table})"


def estimator_from_config(config: dict) -> GroupedRegressor:
    model, search = config["model"], config["search"]
    return GroupedRegressor(
        p=model["p"],
        n=model["n"],
        c=float(model["c"]),
        objective=model["objective"],
        fit_intercept=model["intercept"],
        search=search["method"],
        random_state=search["seed"],
        **ga_settings(config),
    )


def fit_report(estimator: GroupedRegressor, run: Run, model: dict, written: list[Path], intervals=None) -> str:
    """The human-readable table printed by ``groupfit fit``."""
    unit = "µm" if estimator.objective == "sae" else "µm²"
    search = estimator.search_
    lines = [
        f"run     {run.source}: N = {run.n_samples} samples every {run.period:g} s; "
        f"inputs {', '.join(run.temp_names)} -> {run.error_name}",
        f"model   p = {estimator.p}, n = {estimator.n}, c = {estimator.c:g}, M = {estimator.n_coef} "
        f"({'with' if estimator.fit_intercept else 'no'} intercept), objective {estimator.objective}, "
        f"hard groups > {estimator.c * estimator.n_coef:g} samples",
        "search  " + search_summary(search, unit),
        "",
    ]
    names = (["const"] if estimator.fit_intercept else []) + list(run.temp_names)
    header = ["group", "hard", "soft", "serves"] + names + [f"R ({unit})"]
    served = served_ranges(estimator.breaks_, estimator.n_samples_fit_, estimator.n)
    rows = []
    for g, (hard, soft, serve) in enumerate(zip(estimator.hard_groups_, estimator.soft_groups_, served)):
        coefficients = model["coefficients"][g]
        rows.append(
            [str(g + 1), _span(hard), _span(soft), _span(serve)]
            + [f"{v:.5g}" for v in coefficients]
            + [f"{estimator.group_objective_[g]:.4f}"]
        )
    if intervals is not None:
        header.insert(2, f"break {100 * intervals.level:g} % CI")
        for g, row in enumerate(rows):
            row.insert(2, intervals.text_for(estimator.breaks_[g]) if g < len(estimator.breaks_) else "")
    widths = [max(len(r[i]) for r in [header] + rows) for i in range(len(header))]
    for row in [header] + rows:
        lines.append("  ".join(cell.rjust(width) for cell, width in zip(row, widths)))
    metrics = model["training"]
    lines += [
        "",
        f"breaks  {estimator.breaks_}   Rg = {estimator.objective_value_:.6g} {unit}   "
        f"RMS {metrics['rms_um']:.4g} µm   max |e| {metrics['max_um']:.4g} µm",
        f"switch  criterion sensor {model['switching']['criterion']}",
        *(
            [f"breaks  {100 * intervals.level:g} % intervals: {intervals.summary(run.n_samples)}"]
            if intervals is not None
            else []
        ),
        "wrote   " + ", ".join(str(p) for p in written),
    ]
    return "\n".join(lines)


def search_summary(search: dict, unit: str) -> str:
    if search["method"] == "exact":
        return f"exact (dynamic programming): {search['evaluations']} segment costs, {search['seconds']:.2f} s"
    text = (
        f"ga (DEAP, seed {search['seed']}): {search['generations']} generations ({search['stopped']}), "
        f"{search['evaluations']} evaluations, {search['seconds']:.2f} s"
    )
    if "gap_percent" in search:
        text += (
            f"; exact optimum {search['exact_objective']:.6g} {unit} at {search['exact_breaks']}, "
            f"GA gap {search['gap_percent']:.3g} %"
        )
    return text


def _span(pair) -> str:
    return f"{pair[0]}-{pair[1]}"


__all__ = ["run_fit", "estimator_from_config", "fit_report"]
