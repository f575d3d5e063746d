"""``groupfit diagnose``: residual → missing effect → augmented model → error before/after."""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from groupfit import running
from groupfit.commands import common, option_values
from groupfit.commands.recalibrate_option import add_recalibrate_option, recalibrated
from groupfit.commands.replay_readings import with_end_states
from groupfit.data import PERIOD_TOLERANCE, Run, load_run, loading_notes
from groupfit.data_options import add_encoding_option
from groupfit.diagnose import diagnose
from groupfit.diagnose.candidates import HEAT_EXPONENT
from groupfit.diagnose.loop import MIN_EFFECT_RMS_UM, MIN_FURTHER_EFFECT_RMS_UM, MIN_SCORE
from groupfit.diagnose.plot import plot_diagnosis
from groupfit.diagnose.select import ridge_base_model, select_base_model
from groupfit.errors import InputError
from groupfit.fast_response import stage_of, without_stage
from groupfit.heldout.expect import expect_for_model
from groupfit.heldout.selection import SELECTION_METHODS
from groupfit.heldout.span import SPAN_KEY, training_span
from groupfit.io import refuse_repeated
from groupfit.model import ModelFile, time_column
from groupfit.overlap import refuse_overlapping
from groupfit.recordings import RECORDINGS_KEY, recording_entries
from groupfit.runtime import replay_groups
from groupfit.training_checks import DATA_NOTES_KEY


def add_parser(verbs) -> None:
    parser = verbs.add_parser("diagnose", help="trace a model's residual on measured data to a missing effect")
    common.add_model_argument(parser)
    common.add_model_run_options(
        parser,
        "measured run(s) (CSV, XLSX or Parquet): candidates are chosen on them; several runs are held out "
        "one at a time",
        several=True,
    )
    parser.add_argument("--validate", nargs="+", metavar="RUN", help="other run(s), only to judge the result")
    common.add_json_option(parser)
    common.add_quiet_option(parser)
    common.add_range_options(parser, temp=common.VALIDATION_RANGE)
    common.add_clock_options(parser)
    add_encoding_option(parser)
    common.add_glitch_option(parser)
    common.add_out_option(parser, "folder for figures and the new model", default="groupfit-out")
    parser.add_argument(
        "--min-score",
        type=share_value,
        default=MIN_SCORE,
        metavar="F",
        help=f"least out-of-sample share of the residual an effect must explain (default {MIN_SCORE})",
    )
    parser.add_argument(
        "--min-effect",
        type=rms_value,
        default=MIN_EFFECT_RMS_UM,
        metavar="UM",
        help=f"least residual RMS in µm the first effect must remove out of sample (default {MIN_EFFECT_RMS_UM})",
    )
    parser.add_argument(
        "--min-further-effect",
        type=rms_value,
        default=MIN_FURTHER_EFFECT_RMS_UM,
        metavar="UM",
        help="least residual RMS in µm every further effect must remove out of sample, at least --min-effect "
        f"(default {MIN_FURTHER_EFFECT_RMS_UM})",
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
        help="also try low-passes, derivatives and delays of the model's own inputs (under the every-fold test) "
        "and of unused temperature sensors",
    )
    parser.add_argument(
        "--select",
        choices=(*SELECTION_METHODS, "joint"),
        help="first re-select the model's inputs on held-out conditions (for a model that over-fits); joint: "
        "choose the inputs and the first effects together (a global model, p = 0)",
    )
    parser.add_argument(
        "--ridge",
        type=option_values.ridge_value,
        metavar="ALPHA|auto",
        help="first refit the global model (p = 0) with a ridge penalty (auto: chosen on held-out conditions), "
        "for many collinear inputs; effects are then scored and added with the same penalty",
    )
    parser.add_argument(
        "--keep-reference",
        action="store_true",
        help="keep the model's reference sensor (e.g. T_amb) even where absolute readings predict the held-out "
        "conditions clearly better (by default the model is then refitted on absolute readings)",
    )
    parser.add_argument(
        "--ambient",
        type=column_list,
        default=(),
        metavar="COLUMN[,COLUMN]",
        help="columns that are ambient temperatures whatever their names (an air sensor logged as T0): tried as "
        "causes with every transform (default: columns named like T_amb, ambient_C, T_room, air…)",
    )
    parser.add_argument(
        "--continues",
        action="store_true",
        help="each --validate file is the rest of the recording before it (the last --data file, then the "
        "previous --validate file) even though its clock starts again: judged with that history in front",
    )
    add_recalibrate_option(parser)
    parser.set_defaults(handler=run_diagnose)


def column_list(text: str) -> tuple[str, ...]:
    columns = tuple(c.strip() for c in text.split(",") if c.strip())
    if not columns:
        raise argparse.ArgumentTypeError(f"{text!r}: give one or more column names, separated by commas")
    twice = [c for k, c in enumerate(columns) if c in columns[:k]]
    if twice:
        raise argparse.ArgumentTypeError(f"{text!r}: names '{twice[0]}' twice; name each column once")
    return columns


def _bounded(low: float, high: float, what: str):
    """An argparse type: a number in [low, high), else one line saying what it must be."""

    def value(text: str) -> float:
        try:
            number = float(text)
        except ValueError:
            number = math.nan
        if not low <= number < high:
            raise argparse.ArgumentTypeError(f"{text!r}: {what}")
        return number

    return value


share_value = _bounded(0.0, 1.0, "a share of the residual, 0 ≤ F < 1 (e.g. 0.1)")
"""--min-score: a share of the residual in [0, 1)."""
rms_value = _bounded(0.0, math.inf, "an RMS in µm, a finite number ≥ 0")
"""--min-effect, --min-further-effect: an RMS in µm, ≥ 0."""


MAX_HEAT_EXPONENT = 10.0
"""The largest heat-law exponent --heat-exponent takes: (x/1000)^10 is 1e7 at 5000 r/min already."""


def heat_exponent(text: str) -> float | str:
    if text == "fit":
        return text
    try:
        value = float(Fraction(text))
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"{text!r}: give a number such as 5/3 or 1.67, or 'fit'") from None
    if not 0 < value <= MAX_HEAT_EXPONENT:
        raise argparse.ArgumentTypeError(
            f"{text!r}: the exponent must be > 0 and at most {MAX_HEAT_EXPONENT:g} (bearing heat against speed is "
            "about 5/3; a larger power overflows at the speeds of a run)"
        )
    return value


def load_measured(path: str, model: dict[str, Any], time: str, *, next_run: bool = False, **clock) -> Run:
    """A run of ``--data`` with the model's measured inputs. ``next_run``: read as ``replay`` reads a run (a
    ``--validate`` run, or a ``--data`` run as logged in front of one that continues it): temperatures outside the
    plausible range kept as faults of the run-time rule, temperature glitches kept as logged."""
    derived = {d["name"] for d in model.get("derived_inputs", [])}
    measured = [t for t in model["temps"] if t not in derived]
    run = load_run(
        path,
        temps=measured,
        time=time,
        error=model["error"],
        allow_nonfinite=True,
        check_ranges=True,
        temps_as_faults=next_run,
        **clock,
    )
    period = float(model["sampling_period_s"])
    if abs(run.period - period) > PERIOD_TOLERANCE * period:
        raise InputError(
            f"{run.source}: sampled every {run.period:g} s but the model every {period:g} s; "
            "resample the run to the model's period (--resample SECONDS)"
        )
    missing = np.isnan(run.error)
    bad = ~np.isfinite(run.error) & ~missing if model["p"] == 0 else ~np.isfinite(run.error)
    if bad.any():
        fix = (
            "leave the cell empty where the error was not measured, or drop those rows"
            if model["p"] == 0
            else "a grouped model's residual needs the error on every row: drop those rows"
        )
        raise InputError(
            f"{run.source}: row {int(np.flatnonzero(bad)[0]) + 1}, error column '{model['error']}' is not finite "
            f"({int(bad.sum())} rows); {fix}"
        )
    if missing.all():
        raise InputError(f"{run.source}: error column '{model['error']}' is empty on every row; diagnose needs it")
    return run


def modelling_runs_as_logged(
    args: argparse.Namespace, model: dict[str, Any], time: str, clock: dict[str, Any]
) -> list[Run] | None:
    """The ``--data`` runs with their temperature glitches kept as logged, named, not interpolated as for the
    fit: a ``--validate`` run that continues them has them in front so, as ``replay`` reads the modelling file and
    as the controller met the readings. None where the runs loaded serve (no ``--validate``, ``--keep-glitches``)."""
    if not args.validate or args.keep_glitches:
        return None
    return [load_measured(path, model, time, next_run=True, **clock, drop_glitches=True) for path in args.data]


def refuse_too_short(runs: list[Run], model: dict[str, Any]) -> None:
    """Refuse data too short to refit the model's coefficients on part of it: fewer than twice their number
    and one more samples in all."""
    coefficients = len(model["temps"]) + (1 if model.get("intercept", True) else 0)
    least = 2 * coefficients + 1
    total = sum(run.n_samples for run in runs)
    if total < least:
        raise InputError(
            f"{runs[0].source}: {total} sample(s) in all; diagnose refits the model's {coefficients} coefficients on "
            f"parts of the data and needs at least {least}: record a longer run, or give several with --data"
        )


def run_diagnose(args: argparse.Namespace) -> int:
    common.plan_outputs(
        args,
        args.model,
        args.data,
        args.validate,
        folder=args.out,
        files=("model_augmented.json", "model_recalibrated.json", "diagnose.png"),
    )
    given = ModelFile.load(args.model)
    if given.position is not None:
        raise InputError(
            f"{args.model}: a position model (column '{given.position.column}'); diagnose searches position-free "
            "models and would drop its position terms: score it with replay on its table of check runs, and refit "
            "it with fit --position"
        )
    model = without_stage(given).to_dict()  # effects are sought on the model itself
    stage_note = (
        "\nnote    the model's fast-response stage is set aside: before and after are the models without it "
        "(replay of the model file serves it); a model written gets its stage chosen again"
        if stage_of(given) is not None
        else ""
    )
    time = args.time or time_column(model)
    clock = {**common.clock_options(args), **common.range_options(args), "time_is_default": args.time is None}
    glitches = {"drop_glitches": not args.keep_glitches}
    refuse_repeated([*args.data, *(args.validate or [])], "as data (--data, --validate)")
    if args.continues and not args.validate:
        raise InputError("--continues: says each --validate file continues the one before it; give --validate RUN")
    if args.keep_reference and model.get("reference") in (None, "start"):
        raise InputError(
            f"--keep-reference: {args.model} has no reference sensor to keep (absolute readings or 'start')"
        )
    with running.stage("loading", enabled=not args.quiet):
        data = [load_measured(path, model, time, **clock, **glitches) for path in args.data]
        validate = [
            load_measured(path, model, time, next_run=True, **clock, **glitches) for path in args.validate or []
        ]
        data_as_logged = modelling_runs_as_logged(args, model, time, clock)
    refuse_too_short(data, model)
    refuse_overlapping([*data, *validate], "as data (--data, --validate)")
    common.print_notes([*data, *validate], common.report_stream(args))
    out_dir = common.check_output_dir(args.out)
    start = model
    selection = None
    joint = args.select == "joint"
    if joint and args.ridge is not None:
        raise InputError("--select joint and --ridge: the joint selection fits by least squares; give one of them")
    if args.select and not joint:
        start, selection = select_base_model(model, data, args.select)
    ridge = None
    if args.ridge is not None:
        start, ridge = ridge_base_model(start, data, args.ridge)
    with running.stage("diagnosis", enabled=not args.quiet):
        result = diagnose(
            start,
            data,
            validate or None,
            live_rule=replay_groups,
            min_score=args.min_score,
            min_effect_rms_um=args.min_effect,
            min_further_effect_rms_um=args.min_further_effect,
            heat_exponent=args.heat_exponent,
            own_transforms=args.own_transforms,
            select_jointly=joint,
            baseline=model,
            check_reference=not args.keep_reference,
            ambient=args.ambient,
            validation_continues=args.continues,
            data_as_logged=data_as_logged,
        )
    if selection is not None:
        result = replace(result, selection=selection)
    result = replace(result, ridge=ridge)

    with running.stage("next-run estimate", enabled=not args.quiet):
        expectations = {"before": expect_for_model(model, data)}
        expectations["after"] = expect_for_model(result.model, data) if result.changed else expectations["before"]
    if result.changed and expectations["after"] is not None:
        training = {**(result.model.training or {}), **expectations["after"].training()}
        result = replace(result, model=result.model.replace(training=training))
    recordings = {RECORDINGS_KEY: recording_entries(args.data, data, out_dir)}  # the files it was built on
    loading = loading_notes(data)  # this run's, not the fit's
    training = {k: v for k, v in (result.model.training or {}).items() if k != DATA_NOTES_KEY}
    training = {**training, **recordings, **({DATA_NOTES_KEY: loading} if loading else {})}
    if result.changed:  # the span of the augmented model's inputs, derived ones included: replay checks a run on it
        augmented = ModelFile.coerce(result.model)
        spans = np.vstack([augmented.inputs(run.frame, run.source) for run in data])
        training[SPAN_KEY] = training_span(augmented.temps, spans, [run.frame for run in data], augmented.reference)
    result = replace(result, model=result.model.replace(training=training))
    model_path = Path(args.model)
    written = []
    recal_note = ""
    if result.changed or args.recalibrate not in (None, "auto"):
        with running.stage("recalibration", enabled=not args.quiet):
            augmented, recal_note = recalibrated(
                ModelFile.coerce(result.model), [(r.frame, r.error) for r in data], args.recalibrate or "auto"
            )
        model_path = out_dir / ("model_augmented.json" if result.changed else "model_recalibrated.json")
        with_end_states(augmented, common.clock_options(args)).save(model_path)  # an invalid model is never written
        written.append(model_path)
    figure = out_dir / "diagnose.png"
    runs = {"data": data, **({"validate": validate} if validate else {})}
    plot_diagnosis(result, runs, figure)
    written.append(figure)

    report = {
        **result.to_json(model_path),
        "expected_next_run": {k: e and e.to_json() for k, e in expectations.items()},
    }
    written.append(common.write_json(args.json, report))
    common.commit_outputs()
    summary = result.summary() + recal_note + stage_note + expectation_summary(expectations)
    print(summary + "\nwrote   " + common.wrote_line(written), file=common.report_stream(args))
    return 0


def expectation_summary(expectations: dict) -> str:
    """The expected next-run error of the model before and after the diagnosis, by the estimate ``fit`` uses."""
    lines = []
    for when, expectation in expectations.items():
        if expectation is None:
            lines.append(f"expect  {when}: not estimated (a grouped model on several runs, or too few samples)")
            continue
        value, (low, high) = expectation.expected()
        lines.append(f"expect  {when}: about {value:.3g} µm RMS on the next run (range {low:.3g}-{high:.3g} µm)")
    method = next((e for e in expectations.values() if e is not None), None)
    if method is not None:
        lines.append(f"        ({method.method()})")
        lines += [f"note    {note}" for note in method.notes]
    before, after = expectations["before"], expectations["after"]
    if before is not None and after is not None and after is not before and after.expected()[0] > before.expected()[0]:
        lines.append(
            f"note    the next-run estimate rises with the change ({before.expected()[0]:.3g} → "
            f"{after.expected()[0]:.3g} µm) although the diagnosis's own held-out check adopted it: the two "
            "disagree; replay a next run (groupfit replay) before the model goes onto the machine"
        )
    return "\n" + "\n".join(lines)
