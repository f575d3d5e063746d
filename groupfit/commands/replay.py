"""``groupfit replay``: run the run-time switching rule over a recorded run, sample by sample."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from groupfit import running
from groupfit.ar1.modelfile import is_ar1_file
from groupfit.commands import ar1 as ar1_commands
from groupfit.commands import common
from groupfit.commands.replay_expectation import expectation_check, expectation_line
from groupfit.commands.replay_faults import fault_readings
from groupfit.commands.replay_positions import is_check_run_table, replay_check_runs
from groupfit.commands.replay_probes import (
    add_probe_options,
    probe_columns,
    probe_report,
    probe_schedule,
    probe_summary,
    sample_probe,
)
from groupfit.commands.replay_rate import rate_check
from groupfit.commands.replay_readings import earlier_recordings, load_readings
from groupfit.commands.replay_register import register_check
from groupfit.commands.replay_span import modelling_span, range_check
from groupfit.commands.screw_deploy import run_screw_replay
from groupfit.continuation import picked_up, started_running_notes, with_histories, zero_of
from groupfit.data import loading_notes
from groupfit.data_options import add_encoding_option
from groupfit.error_zero import level_shift, zero_offset
from groupfit.errors import InputError
from groupfit.export.sheet import IntegerForm
from groupfit.glitches import scored_glitches
from groupfit.io import save_figure
from groupfit.metrics import error_metrics
from groupfit.model import ModelFile, time_column
from groupfit.recordings import overlap_note
from groupfit.runtime import FAULT_HELD, FAULT_POSITION, FAULT_SENSOR, Replay, RuleTables, SwitchingRule
from groupfit.runtime.period import period_differs
from groupfit.screw.modelfile import is_screw_file


def add_parser(verbs) -> None:
    replay = verbs.add_parser("replay")
    common.add_model_argument(replay)
    common.add_model_run_options(
        replay, "the recorded run (with the model's temperature columns and the source columns of its derived inputs)"
    )
    replay.add_argument(
        "--error", metavar="COLUMN", help="thermal-error column in µm, or COLUMN*K (default: the model's)"
    )
    replay.add_argument(
        "--continues",
        nargs="+",
        metavar="FILE",
        help="the recording(s) --data continues, in order: replayed first, so that the rule and the derived "
        "inputs carry their state into --data as on the controller (only --data's samples are reported; probe "
        "checks fall on them alone)",
    )
    replay.add_argument(
        "--fresh",
        action="store_true",
        help="start the rule and its derived inputs afresh even when --data continues a modelling file the model "
        "names, by its clock or by a first row that picks up where the file's last left off "
        "(training.recordings; by default that file is replayed first, as --continues does)",
    )
    common.add_clock_options(replay)
    common.add_quiet_option(replay)
    add_encoding_option(replay)
    replay.add_argument(
        "--keep-glitches",
        action="store_true",
        help="where readings are averaged (--resample, readings in bursts), average the error's glitches (readings "
        "that leave their neighbours and come back) in with the others of their period; by default they are left "
        "out of its mean, with a note. A sample read alone is scored as read either way",
    )
    replay.add_argument(
        "--precision",
        choices=("double", "single"),
        default="double",
        help="arithmetic of the rule: double, or single as a PLC REAL computes",
    )
    common.add_register_options(
        replay, "also report the compensation in integer controller counts of this many µm (e.g. 0.1)"
    )
    common.add_source_option(replay)
    add_probe_options(replay)
    common.add_range_options(
        replay,
        temp="a ball-screw run's reading outside is refused; a grouped model's rule takes one as a sensor fault",
        refused="left out of the score as not measured",
    )
    common.add_json_option(replay, "the per-sample result")
    common.add_out_option(replay, "folder for replay.png (switch points against the offline breaks)")
    replay.set_defaults(handler=run_replay)


GROUPED_RULE_OPTIONS = {
    "continues": "--continues",
    "fresh": "--fresh",
    "probe_every": "--probe-every",
    "probe_first": "--probe-first",
    "probe_column": "--probe-column",
    "resolution_um": "--resolution-um",
}
"""Options only the grouped model's run-time rule carries out (a history, probe checks, integer counts)."""


def refuse_options_of_the_grouped_rule(args: argparse.Namespace, kind: str) -> None:
    """Refuse an option the replay of ``kind`` would not carry out, rather than report a result without it."""
    for name, option in GROUPED_RULE_OPTIONS.items():
        if getattr(args, name, None) not in (None, False):
            raise InputError(
                f"{option}: {kind} is replayed without it (a history, probe checks and integer counts are the "
                "grouped model's run-time rule's); leave it out"
            )


def integer_form(args: argparse.Namespace) -> IntegerForm | None:
    """The integer register ``--resolution-um`` (and ``--counts-limit``) asks for; None without it."""
    if args.resolution_um is None:
        if args.counts_limit is not None:
            raise InputError(
                "--counts-limit: the size of an integer register, which --resolution-um asks for; give both"
            )
        return None
    return IntegerForm(args.resolution_um, **({} if args.counts_limit is None else {"limit": args.counts_limit}))


def refuse_ball_screw_options(args: argparse.Namespace) -> None:
    """``--source`` and ``--range-temp`` are a ball-screw model's and run's: a grouped model file holds its
    rule's own plausible temperatures (a reading outside is a sensor fault), an AR(1) model reads none."""
    if args.source is not None:
        raise InputError(f"--source {args.source}: a ball-screw model's heat source; this model file has none")
    if args.range_temp is None:
        return
    holds = (
        "an AR(1) model reads no temperature"
        if is_ar1_file(args.model)
        else "a grouped model file holds its own, and its rule takes a reading outside as a sensor fault"
    )
    raise InputError(
        f"--range-temp {args.range_temp}: the plausible temperatures of a ball-screw run; {holds}; leave it out"
    )


def run_replay(args: argparse.Namespace) -> int:
    out_dir = common.plan_outputs(args, args.model, args.data, args.continues, folder=args.out, files=("replay.png",))
    if is_screw_file(args.model):
        refuse_options_of_the_grouped_rule(args, "a ball-screw model file")
        return run_screw_replay(args)
    refuse_ball_screw_options(args)
    if is_ar1_file(args.model):
        refuse_options_of_the_grouped_rule(args, "an AR(1) model file")
        return ar1_commands.run_replay(args)
    model = ModelFile.load(args.model)
    counts = integer_form(args)
    tables = RuleTables.from_model(model)
    error = args.error or model.error or "error_um"
    clock = common.clock_options(args)
    if is_check_run_table(args.data, tables, args.time or time_column(model), clock.get("encoding")):
        return replay_check_runs(args, model, time=args.time or time_column(model), error=error, clock=clock)
    options = dict(time=args.time or time_column(model), time_is_default=args.time is None, error=error)
    options.update(error_is_default=args.error is None, error_limit=common.range_options(args)["error_limit"])
    options.update(sparse=probe_columns(args.probe_column))
    options.update(common.clock_options(args), **({"drop_glitches": False} if args.keep_glitches else {}))
    with running.stage("loading", enabled=not args.quiet):
        run = load_readings(args.data, tables, **options)
        continued, history, found_note, saved = earlier_recordings(
            args, model, run, lambda path: load_readings(path, tables, **options)
        )
    try:
        rule = SwitchingRule(model, precision=args.precision, period_s=run.period)
    except InputError as exc:
        raise InputError(f"{run.source}: {exc}") from None
    if saved is not None:
        run = picked_up(run, saved.error_zero_um)
    rows, notes = 0, []
    if history:
        joined, skipped, notes = with_histories(
            [*history[1:], run], history[:1], assume_continued=True, ignore=probe_columns(args.probe_column)
        )
        rows = skipped[-1]
        temps = joined[-1].temps
        run = picked_up(run, zero_of(joined[-1]))  # an error read from the start: from the recording's
    probes = probe_schedule(args, run, continued=bool(history) or saved is not None)
    with running.stage("replay", enabled=not args.quiet):
        if history:
            checks = None if probes is None else np.r_[np.full(rows, np.nan), probes]  # checks on this file only
            replay = rule.replay(temps, checks).tail(rows)
            unchecked = rule.replay(temps).tail(rows) if probes is not None else None
        else:
            state = None if saved is None else saved.state
            replay = rule.replay(run.temps, probes, state)
            unchecked = rule.replay(run.temps, state=state) if probes is not None else None
            if saved is not None:
                rows, continued = saved.samples, [saved.path]
    common.print_notes([run, *history], common.report_stream(args))
    if found_note is not None:
        notes = [found_note] if history or saved else [found_note, *notes]  # the one note of what was continued
    elif not history and run.time[0] > 2 * run.period:
        notes.append(
            overlap_note(model.training, run)
            or f"{run.name}'s clock starts at {run.time[0]:g} s: the rule starts at sample 1 (group 1) here; if the "
            "file is the rest of a recording, give the earlier file(s) with --continues FILE"
        )
    if not history and saved is None:
        notes += started_running_notes([run], [0], model.derived_inputs or (), lag_of="the derived input's")
    for note in notes:
        print(f"note     {note}", file=common.report_stream(args))
    data = replay_result(model, rule.tables, run, replay, args.model, counts, history_samples=rows)
    data["continues"] = [str(path) for path in continued]
    data["data_notes"] = loading_notes([run, *history])
    residual = residuals(run, replay)
    without = residual if unchecked is None else residuals(run, unchecked)  # the residual without probe checks
    if probes is not None:
        scored = without[np.isfinite(without)] if without is not None else np.empty(0)
        rms_without = float(np.sqrt(np.mean(scored**2))) if scored.size else None
        data["probes"] = probe_summary(args, replay, probes, rms_without, run.period)
    data.update(expectation_check(model.training, data, args.data))
    span = range_check(model, run, replay)
    clamped, clamp_note = clamp_check(rule.tables, replay)
    glitches, glitch_notes = scored_glitches(run.error, residual)
    moved = next((b for b in span.get("beyond_modelling_range", []) if b.get("reference")), None)
    spanned = sum(name in modelling_span(model) for name in model.temps)  # the measured inputs, not derived ones
    shifted = level_shift(span.get("beyond_modelling_range", []), spanned)
    expected_rms = (model.training or {}).get("expected_next_run_rms_um")
    offset, offset_notes = zero_offset(without, expected_rms, moved, shifted)
    register, register_notes = register_check(counts, residual, replay)
    out_of_range, fault_notes = fault_readings(rule.tables, run.temps, replay.fault)
    notes = span.get("notes", []) + fault_notes + ([clamp_note] if clamp_note else []) + glitch_notes + offset_notes
    lagging, lag_notes = rate_check(run.error, replay)
    notes += register_notes + lag_notes
    extra = {**span, **out_of_range, **glitches, **offset, **register, **lagging, "clamped_samples": clamped}
    result = ReplayResult({**data, **extra, **({"notes": notes} if notes else {})})
    with running.stage("writing the outputs", enabled=not args.quiet):
        written = []
        if out_dir is not None:
            figure = out_dir / "replay.png"
            plot_replay(run, rule.tables, replay, model, figure)
            written.append(figure)
        common.finish_outputs(args, result.summary(), result.to_json(), written)
    return 0


@dataclass(frozen=True)
class ReplayResult:
    """A replayed run: the ``--json`` object and the summary ``groupfit replay`` prints."""

    data: dict[str, Any]

    def to_json(self) -> dict[str, Any]:
        return self.data

    def summary(self) -> str:
        return replay_report(self.data)


def clamp_check(tables: RuleTables, replay: Replay) -> tuple[int, str | None]:
    """On how many samples a clamp held the compensation short of the model's prediction, and a note when any did
    (None when none did).

    The residual counts what the clamp left (:func:`residuals`): a next run
    beyond the modelling run's error can reach the clamp, which the rule sets
    from the modelling run's predictions. Probe checks may carry the output
    beyond it, by up to the recalibration's offset bound.
    """
    clamped = int(np.sum(replay.clamped))
    if not clamped:
        return 0, None
    return clamped, (
        f"the model's prediction went beyond the compensation's clamp [{tables.comp_min_um:g}, "
        f"{tables.comp_max_um:g}] µm on {clamped} sample(s); the residual counts the error the clamp left (probe "
        f"checks may carry the output on to [{tables.output_min_um:g}, {tables.output_max_um:g}] µm). If the "
        "machine allows a larger correction, widen switching.comp_min_um / comp_max_um in the model file"
    )


def residuals(run, replay: Replay) -> np.ndarray | None:
    """The error the compensation leaves: measured error + the compensation's target (``−ŷ`` and the probe
    correction, within the rule's clamps); NaN where the error is missing or the rule was in sensor fault.

    The clamps bound what the machine can correct, so a prediction beyond
    them counts only up to them. The rate limit does not count: it shapes how
    the output reaches its target (from 0 at power-on), not what the model predicts.
    """
    if run.error is None:
        return None
    residual = run.error + replay.target_um
    residual[(replay.fault & FAULT_SENSOR) != 0] = np.nan
    residual[~np.isfinite(residual)] = np.nan
    return residual


def offline_groups(model: ModelFile, n_samples: int) -> np.ndarray:
    """1-based group the offline model serves at each sample index."""
    return model.serving_groups(n_samples) + 1


def replay_result(
    model: ModelFile, tables: RuleTables, run, replay: Replay, model_path, counts=None, *, history_samples: int = 0
) -> dict[str, Any]:
    """The ``--json`` object: per-sample decisions plus a summary.

    ``counts`` (an :class:`groupfit.export.sheet.IntegerForm`) adds each
    sample's compensation in integer controller counts. ``history_samples``:
    samples replayed before the run (``--continues``); the rule's sample count
    at the run's sample ``i`` is ``history_samples + i``.
    """
    residual = residuals(run, replay)
    switch_names = {0: None, 1: "criterion", 2: "forced"}
    samples = []
    for k in range(run.n_samples):
        sample = {
            "i": k + 1,
            "time_s": float(run.time[k]),
            "group": int(replay.group[k]),
            "prediction_um": float(replay.prediction_um[k]),
            "compensation_um": float(replay.compensation_um[k]),
            "fault": int(replay.fault[k]),
            "switch": switch_names[int(replay.switched[k])],
        }
        if counts is not None:
            sample["compensation_counts"] = counts.counts(replay.compensation_um[k])
        sample["residual_um"] = None if residual is None or np.isnan(residual[k]) else float(residual[k])
        if replay.probe is not None and replay.probe[k]:
            sample["probe"] = sample_probe(replay, k)
        samples.append(sample)
    scored = residual[~np.isnan(residual)] if residual is not None else np.empty(0)
    metrics = (
        {key: error_metrics(scored)[key] for key in ("rms_um", "max_um", "R_um")}
        if scored.size
        else {"rms_um": None, "max_um": None, "R_um": None}
    )
    offline = offline_groups(model, history_samples + run.n_samples)[history_samples:]
    return {
        "model": str(model_path),
        "run": run.source,
        "n_samples": run.n_samples,
        "history_samples": history_samples,
        "sampling_period_s": run.period,
        "model_period_s": float(model.sampling_period_s),
        "rescaled": period_differs(model, run.period),
        "samples": samples,
        **metrics,
        "scored_samples": int(scored.size),
        "measured_samples": int(np.isfinite(run.error).sum()) if run.error is not None else 0,
        "switches": replay.switch_samples(),
        "offline_breaks": list(tables.breaks),
        "offline_switch_samples": list(tables.window_first),
        "windows": [[a, b] for a, b in zip(tables.window_first, tables.window_last)],
        "samples_off_offline_group": int(np.sum(replay.group != offline)),
        "faults": {
            "held_samples": int(np.sum((replay.fault & FAULT_HELD) != 0)),
            "sensor_fault_samples": int(np.sum((replay.fault & FAULT_SENSOR) != 0)),
            **(
                {"position_clamped_samples": int(np.sum((replay.fault & FAULT_POSITION) != 0))}
                if tables.has_position
                else {}
            ),
        },
        "nonfinite_readings": int(np.sum(~np.isfinite(run.temps))),
    }


def replay_report(result: dict[str, Any]) -> str:
    """The human-readable summary printed by ``groupfit replay`` (without the files it wrote)."""
    rescaled = result.get("rescaled", False)
    lines = [
        f"run      {result['run']}: {result['n_samples']} samples every {result['sampling_period_s']:g} s"
        + (f" (the model's {result['model_period_s']:g} s rescaled to it)" if rescaled else "")
        + (
            f", after {result['history_samples']} samples of the recording it continues"
            if result.get("history_samples")
            else ""
        ),
        "switches "
        + (
            ", ".join(
                f"{s['from']}->{s['to']} at sample {s['i']}{' (forced)' if s['forced'] else ''}"
                for s in result["switches"]
            )
            or "none"
        ),
        f"offline  switches at samples {result['offline_switch_samples']} (breaks {result['offline_breaks']}"
        f"{'; samples of the whole recording' if result.get('history_samples') else ''}); "
        f"{result['samples_off_offline_group']} sample(s) served by another group than offline",
        f"faults   {result['faults']['held_samples']} sample(s) on held readings, "
        f"{result['faults']['sensor_fault_samples']} in sensor fault (safe output)"
        + (
            f", {result['faults']['position_clamped_samples']} at a position clamped to the travel"
            if "position_clamped_samples" in result["faults"]
            else ""
        ),
    ]
    lines.append(common.residual_line(result))
    if "probes" in result:
        lines.append(probe_report(result))
    if "expected_next_run" in result:
        lines.append(expectation_line(result["expected_next_run"]))
    lines += [f"note     {note}" for note in result.get("notes", [])]
    return "\n".join(lines)


def plot_replay(run, tables: RuleTables, replay: Replay, model: ModelFile, path: Path) -> None:
    """Error and prediction over time; below, the group in service against the offline grouping."""
    from matplotlib.figure import Figure

    hours = run.time / 3600.0
    offline = offline_groups(model, run.n_samples)
    fig = Figure(figsize=(9, 6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.6]})
    if run.error is not None:
        top.plot(hours, run.error, color="black", lw=1.5, label="measured error")
    shown = np.where((replay.fault & FAULT_SENSOR) != 0, np.nan, replay.prediction_um)
    top.plot(hours, shown, color="tab:red", lw=1.1, ls="--", label="run-time prediction")
    top.plot(hours, -replay.compensation_um, color="tab:green", lw=0.9, label="−compensation (clamped, rate-limited)")
    faulty = np.flatnonzero(replay.fault)
    if faulty.size:
        top.plot(hours[faulty], np.zeros(faulty.size), "x", color="tab:orange", ms=4, label="fault")
    top.set_ylabel("thermal error (µm)")
    top.legend(loc="best", fontsize=8)
    top.set_title(f"{run.name}: run-time switching (criterion {tables.criterion})")

    bottom.step(hours, offline, where="post", color="tab:blue", lw=1.0, ls=":", label="offline group (by index)")
    bottom.step(hours, replay.group, where="post", color="tab:red", lw=1.2, label="run-time group")
    last = len(hours) - 1
    for k, (first, final) in enumerate(zip(tables.window_first, tables.window_last)):
        if first - 1 <= last:
            bottom.axvspan(
                hours[first - 1],
                hours[min(final - 1, last)],
                color="tab:blue",
                alpha=0.12,
                label="switch window" if k == 0 else None,
            )
    for k, b in enumerate(tables.breaks):
        if b - 1 <= last:
            bottom.axvline(hours[b - 1], color="tab:blue", lw=0.8, label="offline break" if k == 0 else None)
    labelled = set()
    for s in replay.switch_samples():
        kind = "forced switch" if s["forced"] else "criterion switch"
        bottom.plot(
            hours[s["i"] - 1],
            s["to"],
            "v" if s["forced"] else "o",
            color="tab:red",
            ms=5,
            label=None if kind in labelled else kind,
        )
        labelled.add(kind)
    bottom.set_yticks(range(1, tables.n_groups + 1))
    bottom.set_ylabel("group")
    bottom.set_xlabel("time (h)")
    bottom.legend(loc="best", fontsize=8)
    save_figure(fig, path, dpi=120)


__all__ = ["ReplayResult", "load_readings", "run_replay", "replay_result", "plot_replay"]
