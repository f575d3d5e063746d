"""``groupfit replay`` of a position model on a table of check runs: every row scored at its own position.

A long table (several rows per time stamp, one per position) or a wide one
(``err_P<mm>`` columns) is what ``fit --position`` reads (docs/position.md).
Averaging a check run's rows, as a log read in bursts is averaged, would
average its positions and drop every position term. Here the check runs are
the rule's samples, as in the fit, and the rule is replayed once per measured
position, as if the axis stood there through the run; every row is scored
against the replay at its own position and check run. Without breaks, lags
or a dead band this is the fit's own in-sample evaluation.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from typing import Any

import numpy as np

from groupfit.commands import common
from groupfit.commands.replay_faults import fault_readings
from groupfit.commands.replay_readings import load_readings
from groupfit.commands.replay_span import beyond_modelling_range, modelling_span, span_readings
from groupfit.data import ERROR_LIMIT_UM, PERIOD_TOLERANCE, Run
from groupfit.errors import InputError
from groupfit.metrics import error_metrics
from groupfit.model import ModelFile
from groupfit.position import PositionRun, load_position_run, wide_columns
from groupfit.readtable import read_table
from groupfit.runtime import FAULT_HELD, FAULT_POSITION, FAULT_SENSOR, Replay, RuleTables, SwitchingRule
from groupfit.runtime.period import period_differs

STREAM_ONLY_OPTIONS = {
    "continues": "--continues",
    "fresh": "--fresh",
    "probe_every": "--probe-every",
    "probe_first": "--probe-first",
    "probe_column": "--probe-column",
    "resolution_um": "--resolution-um",
    "out": "--out",
}
"""Options of a replay over a stream of samples, which a table of check runs scored row by row does not take."""


def is_check_run_table(path, tables: RuleTables, time: str, encoding: str | None = None) -> bool:
    """Whether ``path`` is a position model's table of check runs: a long table (its position column, and rows
    that share a time stamp) or a wide one (``err_P<mm>`` columns and no position column)."""
    if not tables.has_position:
        return False
    frame, _, label = read_table(path, encoding=encoding)
    if tables.position_name not in frame.columns:
        return bool(wide_columns(frame, label))
    return time in frame.columns and bool(frame[time].dropna().duplicated().any())


def refuse_stream_options(args: argparse.Namespace) -> None:
    """Refuse an option that a replay over a stream carries out and a table of check runs would leave undone."""
    for name, option in STREAM_ONLY_OPTIONS.items():
        if getattr(args, name, None) not in (None, False):
            raise InputError(
                f"{option}: {args.data} is a table of check runs at several positions, scored row by row without "
                "it; give a stream of the axis' readings (one row per sample) to replay it with this option, or "
                "leave it out"
            )


def load_check_runs(args: argparse.Namespace, tables: RuleTables, *, time: str, error: str, clock: dict):
    """The table's check runs and rows (:func:`groupfit.position.load_position_run`), its error beyond
    ``--range-error`` (default :data:`groupfit.data.ERROR_LIMIT_UM`) left out of the score as not measured, as on
    a stream, with a note."""
    error_limit = common.range_options(args)["error_limit"]
    prun = load_position_run(
        args.data,
        tables.position_name,
        temps=list(tables.raw_names[: tables.n_measured]),
        time=time,
        error=error,
        temp_range=None,
        error_limit=None,
        period_tolerance=clock.get("period_tolerance", PERIOD_TOLERANCE),
        resample=clock.get("resample"),
    )
    return without_implausible_rows(prun, ERROR_LIMIT_UM if error_limit is None else error_limit)


def without_implausible_rows(prun: PositionRun, limit: float) -> PositionRun:
    """``prun`` with its rows' error beyond ±``limit`` µm taken as not measured (NaN), and a note naming the
    rows of the file (:func:`groupfit.data.without_implausible_errors` on a stream)."""
    beyond = np.flatnonzero(np.abs(prun.error) > limit)
    if not beyond.size:
        return prun
    file_row = np.arange(prun.error.size) if prun.file_row is None else prun.file_row
    beyond = beyond[np.argsort(file_row[beyond], kind="stable")]
    rows = ", ".join(str(i + 1) for i in file_row[beyond[:5]]) + (" …" if beyond.size > 5 else "")
    label = prun.run.source.removesuffix(" (check runs)")
    note = (
        f"{label}: {beyond.size} reading(s) of the error beyond ±{limit:g} µm (row {rows}, "
        f"{prun.error[beyond[0]]:g} µm first): not a thermal error, left out of the score as not measured"
    )
    error = prun.error.copy()
    error[beyond] = np.nan
    return replace(prun, error=error, run=replace(prun.run, notes=(*prun.run.notes, note)))


def rows_at(prun: PositionRun, position: float) -> np.ndarray:
    """Every check run's row at ``position`` (its first row where it has none there), as indices of ``prun.rows``."""
    index = np.searchsorted(prun.check, np.arange(prun.run.n_samples))
    here = np.flatnonzero(prun.position == position)[::-1]  # reversed: the first of two rows at one position wins
    index[prun.check[here]] = here
    return index


def run_at(prun: PositionRun, tables: RuleTables, position: float, *, time: str, error: str) -> Run:
    """The check runs as the rule reads them with the axis at ``position``: each check run read on its own row
    there (a reading missing on that row is the rule's fault there only, as on a stream), its ``temps`` the
    rule's readings (measured inputs, then sources; the position reading set to ``position``)."""
    frame = prun.run.frame if prun.rows is None else prun.rows.iloc[rows_at(prun, position)].reset_index(drop=True)
    frame = frame.assign(**{tables.position_name: 0.0})
    run = load_readings(frame, tables, time=time, error=error, name=prun.run.source, error_limit=np.inf)
    run.temps[:, tables.position_reading] = position
    return run


def row_residuals(model: ModelFile, prun: PositionRun, *, precision: str = "double") -> np.ndarray:
    """Every row's residual (error + the rule's target at its position and check run; NaN in sensor fault) as
    :func:`replay_check_runs` scores it."""
    names = {"time": prun.run.time_name, "error": prun.run.error_name or "error_um"}
    _, rows = replay_at_positions(model, prun, RuleTables.from_model(model), precision=precision, **names)
    residual = prun.error + rows["target_um"]
    residual[(rows["fault"] & FAULT_SENSOR) != 0] = np.nan
    return residual


ROW_FIELDS = ("target_um", "fault", "clamped", "prediction_um")
"""What :func:`replay_at_positions` keeps of the replay at every row's position and check run."""


def replay_at_positions(
    model: ModelFile, prun: PositionRun, tables: RuleTables, *, precision: str, time: str, error: str
) -> tuple[Replay, dict[str, np.ndarray]]:
    """The rule over the check runs with the axis at each measured position in turn: the replay at the first
    position (its groups and switches; the position changes neither) and, for every row, the target, the
    fault and the clamp of the replay at its own position and check run, the rule's readings there, and the
    model's inputs and reference reading there (``span``: None when they cannot be formed)."""
    if model.breaks and period_differs(model, prun.run.period):  # a table cannot be averaged to the model's period
        raise InputError(
            f"check runs every {prun.run.period:g} s, the model's period is "
            f"{float(model.sampling_period_s):g} s: a grouped model (p = {len(model.breaks)}) switches by sample "
            "count, exact only at its own period, and a table's check runs cannot be averaged without mixing their "
            "positions; record the check runs at the model's period, or fit a model on this table"
        )
    n = prun.error.size
    rows: dict[str, Any] = {name: np.zeros(n, dtype=int if name == "fault" else float) for name in ROW_FIELDS}
    rows["clamped"] = rows["clamped"].astype(bool)
    rows["readings"] = np.empty((n, len(tables.raw_names)))
    spans: list = []
    first = None
    for position in prun.positions:
        run = run_at(prun, tables, position, time=time, error=error)
        replay = SwitchingRule(model, precision=precision, period_s=prun.run.period).replay(run.temps)
        first = replay if first is None else first
        here = prun.position == position
        checks = prun.check[here]
        for name in ROW_FIELDS:
            rows[name][here] = getattr(replay, name)[checks]
        rows["readings"][here] = run.temps[checks]
        spans.append((here, checks, span_readings(model, run.frame, run.source)))
    rows["span"] = rows_span(spans, n)
    return first, rows


def rows_span(spans: list, n: int) -> tuple[np.ndarray, np.ndarray | None] | None:
    """The model's inputs and reference readings of every row, from those of the check runs at each position
    (``(rows, check runs, span_readings)`` per position); None when some position's cannot be formed."""
    if any(readings is None for _, _, readings in spans):
        return None
    inputs = np.empty((n, spans[0][2][0].shape[1]))
    reference = None if spans[0][2][1] is None else np.empty(n)
    for here, checks, (at_inputs, at_reference) in spans:
        inputs[here] = at_inputs[checks]
        if reference is not None:
            reference[here] = at_reference[checks]
    return inputs, reference


def replay_check_runs(args: argparse.Namespace, model: ModelFile, *, time: str, error: str, clock: dict) -> int:
    """``groupfit replay`` of a position model on a table of check runs (module docstring)."""
    refuse_stream_options(args)
    tables = RuleTables.from_model(model)
    prun = load_check_runs(args, tables, time=time, error=error, clock=clock)
    try:
        replay, rows = replay_at_positions(model, prun, tables, precision=args.precision, time=time, error=error)
    except InputError as exc:
        raise InputError(f"{prun.run.source}: {exc}") from None
    residual = prun.error + rows["target_um"]
    residual[(rows["fault"] & FAULT_SENSOR) != 0] = np.nan
    result = check_run_result(args, model, prun, replay, rows, residual)
    result.update(row_checks(model, tables, rows, result["notes"]))
    common.finish_outputs(args, check_run_report(result), result, [])
    return 0


def row_checks(model: ModelFile, tables: RuleTables, rows: dict, notes: list[str]) -> dict[str, Any]:
    """What a stream's replay says of its samples, of the rows: the readings the rule held or met as a sensor
    fault, and the inputs (and reference) beyond the modelling span; ``notes`` with the notes on them added."""
    found, fault_notes = fault_readings(tables, rows["readings"], rows["fault"])
    span = {}
    if modelling_span(model) and rows["span"] is not None:
        span = beyond_modelling_range(model, *rows["span"], rows["fault"])
    return {
        **found,
        **{key: value for key, value in span.items() if key != "notes"},
        "nonfinite_readings": int(np.sum(~np.isfinite(rows["readings"]))),
        "notes": [*notes, *span.get("notes", []), *fault_notes],
    }


def check_run_result(args, model: ModelFile, prun: PositionRun, replay: Replay, rows, residual) -> dict[str, Any]:
    """The ``--json`` object of a table of check runs: one entry per row, the residual over the rows."""
    scored = residual[np.isfinite(residual)]
    metrics = error_metrics(scored) if scored.size else {"rms_um": None, "max_um": None, "R_um": None}
    run = prun.run
    notes = [
        f"{args.data} holds {prun.positions.size} positions per check run: every row is scored at its own position "
        "(the rule replayed over the check runs once per position, as if the axis stood there), not averaged "
        "into one sample",
        *run.notes,
    ]
    clamped = int(np.sum(rows["clamped"]))
    if clamped:
        notes.append(f"the model's clamp held the compensation short of its prediction on {clamped} row(s)")
    samples = [
        {
            "i": k + 1,
            "check_run": int(prun.check[k]) + 1,
            "time_s": float(run.time[prun.check[k]]),
            "position_mm": float(prun.position[k]),
            "group": int(replay.group[prun.check[k]]),
            "prediction_um": float(rows["prediction_um"][k]),
            "target_um": float(rows["target_um"][k]),
            "fault": int(rows["fault"][k]),
            "residual_um": None if np.isnan(residual[k]) else float(residual[k]),
        }
        for k in range(prun.error.size)
    ]
    return {
        "model": str(args.model),
        "run": run.source,
        "n_samples": run.n_samples,
        "check_runs": run.n_samples,
        "rows": int(prun.error.size),
        "positions_mm": [float(p) for p in prun.positions],
        "sampling_period_s": run.period,
        "model_period_s": float(model.sampling_period_s),
        "rescaled": period_differs(model, run.period),
        "samples": samples,
        **{key: metrics[key] for key in ("rms_um", "max_um", "R_um")},
        "scored_samples": int(scored.size),
        "measured_samples": int(np.isfinite(prun.error).sum()),
        "switches": replay.switch_samples(),
        "clamped_samples": clamped,
        "faults": {
            "held_rows": int(np.sum((rows["fault"] & FAULT_HELD) != 0)),
            "sensor_fault_rows": int(np.sum((rows["fault"] & FAULT_SENSOR) != 0)),
            "position_clamped_rows": int(np.sum((rows["fault"] & FAULT_POSITION) != 0)),
        },
        "notes": notes,
    }


def check_run_report(result: dict[str, Any]) -> str:
    """The printed summary of a table of check runs replayed row by row."""
    switches = ", ".join(f"{s['from']}->{s['to']} at check run {s['i']}" for s in result["switches"]) or "none"
    faults = result["faults"]
    lines = [
        f"run      {result['run']}: {result['check_runs']} check runs every {result['sampling_period_s']:g} s at "
        f"{len(result['positions_mm'])} positions ({result['rows']} rows)",
        f"switches {switches}",
        f"faults   {faults['held_rows']} row(s) on held readings, {faults['sensor_fault_rows']} in sensor fault (safe "
        f"output), {faults['position_clamped_rows']} at a position clamped to the travel",
    ]
    if result["rms_um"] is None:
        lines.append("residual none: no row scored (every row in sensor fault: the rule's safe output)")
    else:
        lines.append(
            f"residual RMS {result['rms_um']:.4g} µm, max |e| {result['max_um']:.4g} µm over "
            f"{result['scored_samples']} row(s)"
        )
    lines += [f"note     {note}" for note in result["notes"]]
    return "\n".join(lines)


__all__ = ["is_check_run_table", "replay_check_runs", "row_residuals", "run_at"]
