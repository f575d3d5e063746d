"""``groupfit fit``: optimise the hard breaks, fit the soft groups, save the model."""

from __future__ import annotations

import argparse
from dataclasses import dataclass, replace

import numpy as np

from groupfit import running
from groupfit.commands import ar1_fit as ar1_commands
from groupfit.commands import common, fit_mlr, reference_options, replay_readings
from groupfit.commands.fit_options import add_fit_arguments, refuse_unused_options
from groupfit.commands.fit_position import check_position_options, load_position_data, position_model
from groupfit.commands.recalibrate_option import recalibrated
from groupfit.data import Run, join_runs, loading_notes, measured_rows
from groupfit.errors import InputError
from groupfit.fit_budget import segment_table_over
from groupfit.fitting import FitResult, selection_rule
from groupfit.grouping import check_spacing
from groupfit.heldout.check import held_out_check, ridge_setting, select_inputs
from groupfit.heldout.expect import NextRunExpectation, expect_next_run, penalty_disagreement
from groupfit.heldout.nextrun import next_run_splits
from groupfit.heldout.reference_choice import ReferenceChoice, default_reference_choice
from groupfit.heldout.span import SPAN_KEY, training_span
from groupfit.inference.cli import check_block, intervals_from_args
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.select_p import choose_p, exact_path
from groupfit.outputs import GROUPED_MODELS
from groupfit.plots import plot_fit
from groupfit.position import PositionRun
from groupfit.position_plot import plot_position
from groupfit.recordings import RECORDINGS_KEY, recording_entries
from groupfit.reference import START, with_reference
from groupfit.settings import NEXT_RUN, ModelSettings, RunSettings
from groupfit.training_checks import DATA_NOTES_KEY


def add_parser(verbs) -> None:
    fit = verbs.add_parser("fit")
    add_fit_arguments(fit)
    fit.set_defaults(handler=run_fit)


FIT_FILES = ("model.json", "fit.png", "position.png")
"""What fit writes into --out (position.png for a position model)."""


@dataclass(frozen=True)
class FitData:
    """What ``fit`` fits on, as the stages before the search leave it."""

    settings: RunSettings
    runs: list[Run]
    run: Run
    """The runs joined, with the reference applied and the inputs chosen."""
    position_run: PositionRun | None
    estimate_runs: list[Run]
    """The runs' measured rows the next-run estimate is cut from (none for a position model)."""
    input_selection: dict | None = None
    reference_choice: ReferenceChoice | None = None
    """How the default reference was decided (an ambient column that moves), None when it was configured."""
    global_only: bool = False
    """p was not chosen but set to 0: the error is not measured on every row."""


def run_fit(args: argparse.Namespace) -> int:
    if args.model == "ar1":
        return ar1_commands.run_fit(args)
    refuse_unused_options(args)
    config_path, settings = fit_settings(args)
    common.plan_outputs(
        args, config_path, settings.data.path, folder=settings.output_dir, files=FIT_FILES, json_model=GROUPED_MODELS
    )
    model_wanted = settings.model  # p chosen by the next-run estimate: a global model gets the penalty that holds
    penalty_by_default = (
        args.ridge is None and model_wanted.p == "auto" and model_wanted.p_rule == NEXT_RUN and args.backward is None
    )
    data = chosen_inputs(args, prepared_runs(args, settings))
    settings, selection, expectation = decided_p(args, data)
    p_expectation = expectation  # the least-squares candidates p was chosen among, when it was chosen
    model_settings = settings.model
    estimator = GroupedRegressor.from_settings(
        p=model_settings.p,
        n=model_settings.n,
        c=model_settings.c,
        objective=model_settings.objective,
        fit_intercept=model_settings.intercept,
        search=settings.search,
    )
    run, runs, position_run = data.run, data.runs, data.position_run
    frames = [r.frame for r in recordings(settings, runs, run)]
    not_conditions = {run.time_name, run.error_name, *run.temp_names}  # the held-out folds come from the others
    ridge = None
    if args.ridge is not None or (penalty_by_default and model_settings.p == 0 and position_run is None):
        with running.stage("ridge penalty", enabled=not args.quiet):
            ridge = ridge_setting(
                "auto" if args.ridge is None else args.ridge,
                model_settings.p,
                run.temps,
                run.error,
                frames,
                not_conditions,
                fit_intercept=model_settings.intercept,
                default=args.ridge is None,
            )
        estimator.set_params(ridge_alpha=ridge.alpha)
    alpha = ridge.alpha if ridge is not None else 0.0
    out_dir = common.check_output_dir(settings.output_dir)
    progress = common.StageProgress(enabled=not args.quiet)
    fit_run = measured_rows(run)
    try:
        estimator.fit(fit_run.temps, fit_run.error, progress=progress)
        seed = settings.search.seed
        intervals = intervals_from_args(args, estimator, fit_run.temps, fit_run.error, seed, progress)
    finally:
        progress.close()
    model = estimator.to_model_file(run, model_settings.criterion)  # the valid ranges over every row
    expectation, no_estimate = fitted_model_expectation(args, replace(data, settings=settings), expectation, alpha)
    notes = f"\nnote    no next-run estimate: {no_estimate}" if no_estimate else ""
    if alpha > 0 and args.ridge is None and expectation is not None and p_expectation is not None:
        notes += penalty_disagreement(expectation, p_expectation, alpha)
    span = training_span(run.temp_names, run.temps, [run.frame], run.reference)
    training = {**model.training, SPAN_KEY: span}
    if position_run is None:
        training[RECORDINGS_KEY] = recording_entries(settings.data.paths, runs, out_dir)
    if run.notes:
        training[DATA_NOTES_KEY] = loading_notes([run])
    choice = None  # the table p was chosen by, kept apart when the chosen global model got a penalty
    if alpha > 0 and p_expectation is not None and (len(p_expectation.candidates) > 1 or p_expectation.not_tried):
        choice = p_expectation
    if expectation is not None:
        rule = None if selection is None else selection_rule(selection)
        training.update(expectation.model_training(model_settings.p, choice, rule))
    if data.reference_choice is not None:
        training["reference_choice"] = data.reference_choice.to_json()
        if data.reference_choice.scored:
            notes += "\n" + data.reference_choice.line()
        undecided = data.reference_choice.note()
        notes += f"\nnote    {undecided}" if undecided else ""
    model = model.replace(training=training)
    if position_run is not None:
        model, position_notes = position_model(args, model, position_run)
        notes = position_notes + notes
    if fit_run is not run:
        notes += (
            f"\nnote    the error is measured on {fit_run.n_samples} of {run.n_samples} rows: the model is fitted "
            "on those"
        )
    held_out = None
    if position_run is None:
        grouped = model.to_dict() if estimator.p > 0 else None
        with running.stage("held-out check", enabled=not args.quiet):
            held_out = held_out_check(
                run.temps,
                run.error,
                frames,
                not_conditions,
                fit_intercept=model_settings.intercept,
                ridge_alpha=alpha,
                grouped=grouped,
            )
        with running.stage("recalibration", enabled=not args.quiet):
            model, recal_note = recalibrated(model, [(r.frame, r.error) for r in runs], args.recalibrate or "auto")
        notes = recal_note + notes
    with running.stage("end states", enabled=not args.quiet):
        model = replay_readings.with_end_states(model, common.clock_options(args, settings.data))  # after each file
    result = FitResult(
        estimator,
        fit_run,
        model,
        selection,
        data.input_selection,
        intervals,
        ridge,
        held_out,
        expectation=expectation,
        choice=choice,
        no_estimate=no_estimate,
    )
    if estimator.p == 0 and alpha == 0 and position_run is None:
        with running.stage("statistics", enabled=not args.quiet):
            result.statistics = fit_mlr.statistics(fit_run, fit_intercept=model_settings.intercept)
    written = write_fit_outputs(args, out_dir, result, intervals, position_run)
    print(result.summary() + notes + "\nwrote   " + written, file=common.report_stream(args))
    return 0


def fit_settings(args: argparse.Namespace) -> tuple:
    """The configuration's path and its settings with every option ``fit`` was given."""
    config_path, settings = common.settings_with_data_options(args)
    return config_path, settings.given(
        model={
            "p": args.p,
            "pmax": args.pmax,
            "p_rule": args.p_rule,
            "p_target": args.p_target,
            "n": args.n,
            "c": args.c,
            "objective": args.objective,
            "intercept": False if args.no_intercept else None,
            "criterion": args.criterion,
        },
        search={
            "method": args.search,
            "seed": args.seed,
            "certify": {"yes": True, "no": False}.get(args.certify, args.certify),
        },
        output={"dir": args.out},
    )


def recordings(settings: RunSettings, runs: list[Run], run: Run) -> list[Run]:
    """The recordings the next-run estimate, the ridge folds and the reference choice hold out: each file of
    several, or the one log as ``run`` joins it (a log --resample split at its gaps is one recording)."""
    return runs if isinstance(settings.data.path, (list, tuple)) else [run]


def prepared_runs(args: argparse.Namespace, settings: RunSettings) -> FitData:
    """The runs loaded and joined, the reference applied; p = 0 where only a global model can be fitted."""
    position_run = None
    check_position_options(args)
    if args.position:
        position_run = load_position_data(settings.data, args.position)
        runs = [position_run.run]
    else:
        with running.stage("loading", enabled=not args.quiet):
            runs = common.load_configured_runs(settings.data, missing_error=True)
    common.print_notes(runs, common.report_stream(args))
    if settings.model.p == "auto" and (len(runs) > 1 or position_run is not None):
        settings = with_p(settings, 0)  # several runs, or check runs at positions: a global model
    if len(runs) > 1 and settings.model.p != 0:
        split = "" if isinstance(settings.data.path, (list, tuple)) else " (--resample split the log at its gaps)"
        raise InputError(
            f"{len(runs)} runs given{split}: several runs fit a global model, --p 0; a grouped model's "
            "breaks belong to one run (fit it per run and operating condition)"
        )
    run = join_runs(runs)
    reference = reference_options.configured_reference(args, settings, run, runs)
    choice = None
    if position_run is None and reference_options.reference_is_default(args, settings):
        model = settings.model
        p_values = tuple(range(model.pmax + 1)) if model.p == "auto" else (model.p,)
        with running.stage("reference choice", enabled=not args.quiet):
            choice = default_reference_choice(
                recordings(settings, runs, run),
                reference,
                p_values,
                n=model.n,
                c=float(model.c),
                fit_intercept=model.intercept,
            )
        reference = reference if choice is None else choice.reference
    if len(runs) > 1 and reference == START:
        runs = [with_reference(r, START) for r in runs]  # each run's own start
        run = join_runs(runs)
    else:
        run = with_reference(run, reference)
    global_only = settings.model.p == "auto" and bool(np.isnan(run.error).any())
    if global_only:
        settings = with_p(settings, 0)  # an error not on every row: a global model on the measured rows
    check_measured(run, settings.model.p)
    check_block(args, run.n_samples)
    if position_run is not None:
        position_run = replace(position_run, run=run)
        if args.select:
            raise InputError("--select is not available with --position; name the inputs with --temps")
        if args.ridge is not None:
            raise InputError("--ridge is not available with --position: the position terms are fitted by least squares")
    estimate = recordings(settings, runs, run) if position_run is None else []
    estimate_runs = [measured_rows(with_reference(r, reference)) for r in estimate]
    return FitData(settings, runs, run, position_run, estimate_runs, reference_choice=choice, global_only=global_only)


def chosen_inputs(args: argparse.Namespace, data: FitData) -> FitData:
    """The inputs chosen by ``--select`` or ``--backward`` (all of them otherwise); the criterion checked."""
    settings, run, estimate_runs, input_selection = data.settings, data.run, data.estimate_runs, None
    if args.select:
        frames = [r.frame for r in data.runs]
        with running.stage("input selection", enabled=not args.quiet):
            run, input_selection = select_run_inputs(run, frames, args.select, args.sensors, estimate_runs)
        estimate_runs = [with_inputs(r, run.temp_names) for r in estimate_runs]
    elif args.sensors is not None:
        raise InputError("--sensors K needs --select forward|lasso|cluster")
    if args.backward is not None:
        if args.select or data.position_run is not None:
            raise InputError("--backward chooses the inputs itself: not with --select or --position")
        if settings.model.p == "auto":
            settings = with_p(settings, 0)  # backward elimination is for a global regression
        intercept = settings.model.intercept
        run, input_selection = fit_mlr.backward_run(run, args.backward, p=settings.model.p, fit_intercept=intercept)
        estimate_runs = [with_inputs(r, run.temp_names) for r in estimate_runs]
    criterion = settings.model.criterion
    if criterion is not None and criterion not in run.temp_names:
        raise InputError(
            f"switching criterion '{criterion}' (--criterion, [model] criterion) is not a model input; "
            f"choose one of {', '.join(run.temp_names)}"
        )
    return replace(data, settings=settings, run=run, estimate_runs=estimate_runs, input_selection=input_selection)


def decided_p(args: argparse.Namespace, data: FitData) -> tuple:
    """The settings with p decided, the exact path's choice (``--p-rule bic|target``) and the next-run expectation."""
    settings, run = data.settings, data.run
    model = settings.model
    n_coef = run.temps.shape[1] + int(model.intercept)
    if model.p == "auto" and model.p_rule != NEXT_RUN:
        common.check_exact_budget(args, run, n_coef, model.objective, max(model.pmax, 0), "--p auto's exact path")
    elif settings.search.method == "exact" and isinstance(model.p, int):
        common.check_exact_budget(args, run, n_coef, model.objective, model.p, "the exact search")
    selection = expectation = None
    check_spacing(model.n, float(model.c))  # before the estimate, whose refusal would blame the run
    if model.p == "auto" and model.pmax < 0:
        raise InputError(f"--pmax {model.pmax}: the largest p tried must be 0 or more")
    table = None if args.no_budget else segment_table_over(run.n_samples, n_coef, run.period, common.EXACT_BUDGET_BYTES)
    if table is not None and isinstance(model.p, int) and model.p > 0:
        raise InputError(f"{run.source}: {table}, or fit a global model (--p 0); --no-budget runs it anyway")
    if model.p == "auto" and model.p_rule == NEXT_RUN:
        p_values = (0,) if args.ridge is not None or table is not None else tuple(range(model.pmax + 1))
        with running.stage("next-run estimate", enabled=not args.quiet):
            expectation = model_expectation(model, data.estimate_runs, p_values)
        if table is not None:
            print(f"note    only p = 0 was tried: {table}", file=common.report_stream(args))
        settings = with_p(settings, expectation.candidates[expectation.chosen])
    elif model.p == "auto":
        with running.stage("exact path", enabled=not args.quiet):
            selection = select_breaks(model, run)
        settings = with_p(settings, selection["p"])
    elif not isinstance(model.p, int):
        raise InputError(f"p = {model.p!r}: give a whole number or 'auto'")
    return settings, selection, expectation


def write_fit_outputs(args, out_dir, result: FitResult, intervals, position_run) -> str:
    """Write model.json, fit.png (position.png) and the JSON; the report's "wrote" line."""
    run, estimator = result.run, result.estimator
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
    json_path = common.write_json(args.json, result.to_json())
    common.commit_outputs()
    return common.wrote_line([model_path, figure_path, position_figure, json_path])


def with_p(settings: RunSettings, p: int) -> RunSettings:
    """The settings with the number of breaks decided."""
    return settings.given(model={"p": p})


def model_expectation(model: ModelSettings, runs: list[Run], p_values, ridge_alpha: float = 0.0) -> NextRunExpectation:
    """The expected next-run error of the candidates ``p_values`` (:mod:`groupfit.heldout.expect`)."""
    try:
        result = expect_next_run(
            runs, p_values, n=model.n, c=float(model.c), fit_intercept=model.intercept, ridge_alpha=ridge_alpha
        )
    except ValueError as exc:
        remedy = "give --p or record a longer run" if len(p_values) > 1 else "a smaller --p or a longer run gives one"
        raise InputError(f"{runs[0].source}: the next-run estimate: {exc}; {remedy}") from None
    return result


def fitted_model_expectation(
    args: argparse.Namespace, data: FitData, expectation: NextRunExpectation | None, alpha: float
) -> tuple[NextRunExpectation | None, str]:
    """The fitted model's next-run expectation (``expectation`` when it is the chosen candidate's and no penalty
    changed it), and why there is none, when there is none."""
    model = data.settings.model
    if data.position_run is not None:
        return None, position_choices(args, data.settings, data.run)
    if expectation is None or alpha > 0:
        try:
            with running.stage("next-run estimate", enabled=not args.quiet):
                expectation = model_expectation(model, data.estimate_runs, (model.p,), alpha)
        except InputError as exc:
            return None, str(exc)
    if data.global_only:
        measured = int(np.isfinite(data.run.error).sum())
        expectation = expectation.on_measured_rows(measured, data.run.n_samples, model.pmax)
    return expectation, ""


def position_choices(args: argparse.Namespace, settings: RunSettings, run: Run) -> str:
    """What a position model's fit leaves to its defaults instead of the next-run estimate, in words."""
    defaults = []
    if args.p in (None, "auto"):
        defaults.append("p = 0 (--p N searches breaks on the check runs)")
    if reference_options.reference_is_default(args, settings):
        defaults.append(f"the reference {run.reference or 'none'} (--reference none|start|COLUMN sets another)")
    told = ""
    if defaults:
        told = f"; {' and '.join(defaults)} {'are the defaults' if len(defaults) > 1 else 'is the default'}, not chosen"
    return (
        "a position model's check runs are not cut into the operating segments the estimate replays"
        f"{told}; replay the model on another run of check runs (groupfit replay MODEL --data RUN) to measure it"
    )


def with_inputs(run: Run, names) -> Run:
    """The run restricted to the inputs ``names``."""
    keep = [run.temp_names.index(name) for name in names]
    return replace(run, temps=run.temps[:, keep], temp_names=tuple(names))


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


def select_breaks(model: ModelSettings, run: Run) -> dict:
    """Choose p over 0…pmax from the certified optimum of every p."""
    path = exact_path(
        run.temps,
        run.error,
        model.pmax,
        n=model.n,
        c=float(model.c),
        objective=model.objective,
        fit_intercept=model.intercept,
    )
    n_coef = run.temps.shape[1] + int(model.intercept)
    selection = choose_p(path["rss"], path["R"], run.n_samples, n_coef, model.p_rule, model.p_target)
    if selection["p"] is None:
        raise InputError(
            f"no p up to {len(path['R']) - 1} meets the target R = {selection['target_um']:g} µm "
            f"(best: {min(path['R']):.4g} µm); raise --p-target or --pmax"
        )
    selection["R_um"] = path["R"]
    selection["breaks"] = path["breaks"]
    return selection


__all__ = ["run_fit", "select_breaks"]
