"""``groupfit compare``: grouped p = 0…P against global MLR and physics AR(1), on every run."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from groupfit import running
from groupfit.commands import common, option_values, reference_options
from groupfit.comparison import ComparisonSettings, compare_models, in_modelling_order, path_pmax
from groupfit.conditions import SPEED_NAME, heat_level_column, run_operating_columns
from groupfit.continuation import picked_up, with_histories, zero_of
from groupfit.data import Run, join_runs, loading_notes
from groupfit.errors import InputError
from groupfit.fit_budget import projecting, segment_table_over
from groupfit.heldout.reference_choice import default_reference_choice
from groupfit.inference.cli import add_interval_options, check_block, interval_settings
from groupfit.io import refuse_repeated
from groupfit.overlap import refuse_overlapping
from groupfit.plots import plot_hysteresis, plot_r_against_p, plot_run_comparison
from groupfit.probe_intervals import (
    check_intervals_fit,
    check_probe_first,
    interval_plan,
    interval_summary,
    interval_table,
    parse_tolerance,
    plan_summary,
    plot_intervals,
    rounded_interval_notes,
)
from groupfit.reference import with_reference
from groupfit.runtime import replay_groups
from groupfit.settings import CompareSettings


def add_parser(verbs) -> None:
    compare = verbs.add_parser("compare")
    common.add_run_options(compare, range_temp=common.VALIDATION_RANGE)
    compare.add_argument("--validate", nargs="+", metavar="CSV", help="validation runs (not used for fitting)")
    compare.add_argument("--pmax", type=int, help="largest number of breaks compared (default 4)")
    compare.add_argument("--seed", type=option_values.seed_value, help="seed of the genetic algorithm")
    compare.add_argument(
        "--heat",
        metavar="COLUMN|none",
        help="heat-level column of the AR(1) model (default speed_rpm, or [compare] heat; a run without it: its "
        "operating column named as a speed, or its only one); none leaves it out",
    )
    reference_options.add_reference_option(compare)
    compare.add_argument(
        "--continues",
        action="store_true",
        help="each --validate run is the rest of the recording before it (the modelling run, then the previous "
        "--validate run) even though its clock starts again; a run whose clock goes on is detected without it",
    )
    common.add_json_option(compare)
    common.add_out_option(compare, "folder for the figures")
    common.add_quiet_option(compare)
    common.add_budget_option(compare)
    add_interval_options(compare)
    compare.add_argument(
        "--probe-every",
        type=option_values.check_intervals,
        metavar="T,T,…",
        help="also the error against a probe check every T (e.g. 5m,15m,30m,60m,120m; s, m, h or seconds) for "
        "every model on the validation runs, through the offset hold: printed, plotted and in --json",
    )
    compare.add_argument(
        "--probe-first",
        type=float,
        metavar="SECONDS",
        help="with --probe-every: the first check SECONDS after each run's first sample (default: after the first "
        "interval's samples; 0: at the first sample), as replay --probe-first",
    )
    compare.add_argument(
        "--tolerance",
        metavar="UM",
        help="with --probe-every: print per model the longest interval whose RMS with checks is at most UM µm on "
        "every run (and in --json: probe_intervals.plan)",
    )
    compare.set_defaults(handler=run_compare)


def settle_heat_and_conditions(args: argparse.Namespace, settings: ComparisonSettings, runs: list) -> str | None:
    """The AR(1) heat level and the condition columns of a log without the default ``speed_rpm``: its
    operating columns, found as ``fit``'s held-out check finds them; the note that says what was taken."""
    columns = runs[0].frame.columns
    default_heat = args.heat is None and settings.heat == CompareSettings.heat and settings.heat not in columns
    default_conditions = settings.conditions == CompareSettings.conditions and any(
        c not in columns for c in settings.conditions
    )
    if not (default_heat or default_conditions):
        return None
    operating = run_operating_columns(runs)
    if default_conditions:
        settings.conditions = tuple(operating)
    if not default_heat:
        return None
    absent = settings.heat
    settings.heat = heat_level_column(operating)
    if settings.heat is not None:
        why = "operating column named as a speed" if SPEED_NAME.search(str(settings.heat)) else "only operating column"
        return (
            f"AR(1): heat level '{settings.heat}', the run's {why} (the default '{absent}' is absent); "
            "--heat COLUMN names another, --heat none leaves it out"
        )
    speeds = [c for c in operating if SPEED_NAME.search(str(c))]
    which = f"{', '.join(speeds)} are all named as a speed" if speeds else "none is named as a speed"
    found = f"; of its operating columns ({', '.join(operating)}) {which}" if operating else ""
    return f"AR(1): left out: the run has no '{absent}' column, its default heat level{found}; --heat COLUMN names one"


def modelling_runs(data, *, as_logged: bool = False) -> list:
    """The modelling runs: each file of several, or the one log (which --resample may not split at its gaps:
    a grouped model's breaks belong to one run, and the error says so). ``as_logged``: their temperature
    glitches kept as logged (named, not interpolated), as ``replay`` reads a modelling file."""
    options = {"missing_error": True, **({"temps_as_faults": True} if as_logged else {})}
    if len(data.paths) > 1:
        return common.load_configured_runs(data, **options)
    return [common.load_configured_run(data, **options)]


def histories(data, parts: list[Run], reference: str | None) -> list[Run]:
    """The modelling runs as a validation run that continues them has them in front: as the controller met
    them and as ``replay`` reads the modelling file before the run, a temperature glitch kept as logged (the
    fit interpolates it in ``parts``), the inputs taken against ``reference``."""
    if data.keep_glitches or not data.validate:
        return parts
    return [with_reference(part, reference) for part in modelling_runs(data, as_logged=True)]


def validation_runs(data, path) -> list[Run]:
    """The runs of one ``--validate`` file, read as ``replay`` reads a next run: a reading that is not a number,
    or a temperature outside the plausible range (a sensor's fault code, -999 °C), is kept, a sensor fault of the
    run-time rule (held, then not scored: :mod:`groupfit.comparison_faults`), and a temperature's glitch is
    kept as logged, with a note; an implausible error is refused as in a modelling run, and so is an error
    column empty on every row."""
    runs = common.load_configured_runs(
        data, path, missing_error=True, allow_nonfinite=True, check_ranges=True, temps_as_faults=True
    )
    for run in runs:
        if run.error is not None and not np.isfinite(run.error).any():
            raise InputError(
                f"{run.source}: error column '{run.error_name}' is empty on every row; a validation run is scored on it"
            )
    return runs


def global_models_only(args, settings: ComparisonSettings, n_parts: int, modelling: Run, n_coef: int) -> None:
    """No grouped models with several modelling runs (their breaks belong to one run), nor when a grouped model's
    table of segment sums would exceed the memory budget (said in a note)."""
    if n_parts > 1:
        settings.pmax = settings.fit_pmax = 0
    table = segment_table_over(modelling.n_samples, n_coef, modelling.period, common.EXACT_BUDGET_BYTES)
    if table is not None and settings.pmax > 0 and not args.no_budget:
        settings.pmax = settings.fit_pmax = 0
        print(f"note    grouped models left out (--no-budget compares them): {table}", file=common.report_stream(args))


def run_compare(args: argparse.Namespace) -> int:
    config_path, run_settings = common.settings_with_data_options(args)
    run_settings = run_settings.given(
        data={"validate": args.validate},
        compare={"pmax": args.pmax, "heat": args.heat},
        search={"seed": args.seed},
        output={"dir": args.out},
    )
    data = run_settings.data
    if run_settings.compare.pmax < 0:
        raise InputError(f"--pmax {run_settings.compare.pmax}: the largest p compared must be 0 or more")
    check_probe_first(args.probe_first, args.probe_every)
    tolerance = parse_tolerance(args.tolerance, args.probe_every)
    if args.continues and not data.validate:
        raise InputError("--continues: says each --validate run continues the one before it; give --validate RUN")
    runs = [p for p in [*data.paths, *data.validate] if isinstance(p, (str, Path))]
    refuse_repeated(runs, "as data (--data, --validate)")
    common.plan_outputs(
        args,
        config_path,
        data.path,
        list(data.validate),
        folder=run_settings.output_dir,
        files=[
            "R_against_p.png",
            "error_against_check_interval.png",
            *(f"compare_{Path(p).stem}.png" for p in runs),
            *([f"compare_{'+'.join(Path(p).stem for p in data.paths)}.png"] if len(data.paths) > 1 else []),
        ],
    )
    settings = ComparisonSettings.from_settings(run_settings)
    settings.intervals = interval_settings(args)
    if settings.structural_sensor and settings.structural_gain_um_per_K is None:
        raise InputError("[compare] structural_sensor needs structural_gain_um_per_K (µm per K, e.g. α·L)")

    with running.stage("loading", enabled=not args.quiet):
        parts = modelling_runs(data)
    modelling = join_runs(parts)
    n_coef = modelling.temps.shape[1] + int(settings.fit_intercept)
    global_models_only(args, settings, len(parts), modelling, n_coef)
    validation = [run for path in data.validate for run in validation_runs(data, path)]
    refuse_overlapping([*parts, *validation], "as data (--data, --validate)")
    if args.probe_every:
        check_intervals_fit(args.probe_every, args.probe_first, validation or [modelling])
    heat_note = settle_heat_and_conditions(args, settings, [modelling, *validation])
    common.print_notes([modelling, *validation], common.report_stream(args))
    rounded = rounded_interval_notes(args.probe_every or (), validation or [modelling], args.probe_first)
    for note in rounded + ([heat_note] if heat_note else []):
        print(f"note    {note}", file=common.report_stream(args))
    data_notes = loading_notes([modelling, *validation]) + rounded + ([heat_note] if heat_note else [])
    reference = reference_options.configured_reference(args, run_settings, modelling, parts)
    choice = None
    if reference_options.reference_is_default(args, run_settings):
        candidates = tuple(range(settings.fit_pmax + 1))  # as fit decides it
        with running.stage("reference choice", enabled=not args.quiet):
            choice = default_reference_choice(
                parts, reference, candidates, n=settings.n, c=settings.c, fit_intercept=settings.fit_intercept
            )
        reference = reference if choice is None else choice.reference
    parts = [with_reference(part, reference) for part in parts]  # a reference at the start: each run's own
    modelling = join_runs(parts)
    validation = [in_modelling_order(modelling, with_reference(run, reference, faults=True)) for run in validation]
    joined, skipped, notes = with_histories(
        validation, histories(data, parts, reference), assume_continued=args.continues
    )
    validation = [picked_up(run, zero_of(whole)) for run, whole in zip(validation, joined)]  # COLUMN-start
    recordings = {run.name: whole for run, whole, rows in zip(validation, joined, skipped) if rows}
    for note in notes:
        data_notes.append(
            note.replace("derived inputs and run-time state carry their", "run-time switching carries its")
        )
        print(f"note    {data_notes[-1]}", file=common.report_stream(args))
    check_block(args, modelling.n_samples)
    pmax = path_pmax(modelling, settings.pmax)
    over = common.over_budget(args, modelling, n_coef, settings.objective, pmax, "the exact path p = 0…pmax")
    if over is not None:  # the GA's models are compared, the path not certified
        settings.certify_path = False
        data_notes.append(
            f"{over[0]}: the path of R against p is the GA's models, not certified (--no-budget certifies it)"
        )
        print(f"note    {data_notes[-1]}", file=common.report_stream(args))
    out_dir = common.check_output_dir(run_settings.output_dir)
    progress = common.StageProgress(enabled=not args.quiet)
    try:
        result = compare_models(
            parts,
            validation,
            settings,
            live_rule=replay_groups,
            progress=projecting(
                progress,
                asked=settings.pmax,
                budget_s=None if args.no_budget else common.EXACT_BUDGET_SECONDS,
                estimate=lambda line: print(f"estimate {line}", file=sys.stderr, flush=True),
            ),
            recordings=recordings,
            stage=lambda name: running.stage(name, enabled=not args.quiet),
        )
    finally:
        progress.close()

    written = []
    for run in [modelling, *validation]:
        figure = out_dir / f"compare_{run.name}.png"
        role = "modelling run" if run is modelling else f"validation run, grouped by {result.validation_rule}"
        plot_run_comparison(
            run.time,
            run.error,
            result.predictions[run.name],
            figure,
            f"{run.name} ({role})",
            bands=result.bands[run.name],
        )
        written.append(figure)
    figure = out_dir / "R_against_p.png"
    plot_r_against_p(result.path["R"], result.rows, result.runs, figure, certified=result.path.get("certified", True))
    written.append(figure)
    figure = out_dir / f"hysteresis_{modelling.name}.png"
    plot_hysteresis(
        modelling.temps, modelling.temp_names, modelling.error, figure, f"{modelling.name}: error against inputs"
    )
    written.append(figure)

    data, summary = {**result.to_json(), "data_notes": data_notes}, result.summary()
    if choice is not None:
        data["reference_choice"] = choice.to_json()
        if choice.scored:
            summary = choice.line() + "\n" + summary
        undecided = choice.note()
        summary += f"\nnote    {undecided}" if undecided else ""
    if args.probe_every:
        checked = validation or [modelling]
        table = interval_table(
            {run.name: run.error for run in checked},
            result.predictions,
            {run.name: run.period for run in checked},
            args.probe_every,
            args.probe_first,
        )
        figure = out_dir / "error_against_check_interval.png"
        plot_intervals(table, figure, tolerance)
        written.append(figure)
        data["probe_intervals"], summary = table, summary + "\n\n" + interval_summary(table)
        if tolerance is not None:
            table["plan"] = interval_plan(table, tolerance)
            summary += "\n" + plan_summary(table["plan"])
    written.append(common.write_json(args.json, data))
    common.commit_outputs()
    print(summary + "\nwrote   " + common.wrote_line(written), file=common.report_stream(args))
    return 0
