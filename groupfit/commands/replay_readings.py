"""What ``groupfit replay`` reads: a run's readings as the rule takes them, and what came before the run.

A run that continues a modelling recording (by its clock or its first row,
:mod:`groupfit.recordings`) is replayed after that file, as the controller,
which ran through, meets it. Where the file is no longer there, or has
changed since the fit, the rule's state at the file's end, which ``fit`` and
``diagnose`` keep in the model file (``training.recordings[k].end_state``,
:mod:`groupfit.runtime.state`), stands in for it: the run is replayed from
that state, bit for bit as after the file.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from groupfit.commands.replay_probes import probe_columns
from groupfit.continuation import recording_difference
from groupfit.data import ERROR_LIMIT_UM, Run, load_run, numeric_column, without_implausible_errors
from groupfit.error_start import ZERO_KEY
from groupfit.errors import InputError
from groupfit.io import refuse_repeated
from groupfit.model import ModelFile, time_column
from groupfit.position import millimetres_per_unit, position_unit_notes
from groupfit.recordings import continued_recording
from groupfit.runtime import RuleTables, SwitchingRule
from groupfit.runtime.state import capture, restore
from groupfit.training_checks import END_STATE, RECORDINGS_KEY

PRECISIONS = ("double", "single")


def load_readings(
    path, tables: RuleTables, *, time: str, error: str, error_limit: float = ERROR_LIMIT_UM, **clock
) -> Run:
    """A recorded run with the rule's readings as its ``temps``: measured inputs, then sources.

    The measured inputs load as ``groupfit fit`` loads temperatures; the
    source columns of derived inputs (an ambient temperature, a speed, an
    on/off signal) load as they are, non-finite values kept (the rule treats
    them as faults), and a missing one is named with the inputs it feeds. An error column asked for
    (``error_is_default=False`` in ``clock``) and not in the run is refused.
    """
    measured = list(tables.raw_names[: tables.n_measured])
    run = without_implausible_errors(
        load_run(path, temps=measured, time=time, error=error, require_error=False, allow_nonfinite=True, **clock),
        error_limit,
    )
    if run.error is None and clock.get("error_is_default") is False:
        raise InputError(
            f"{run.source}: --error '{error}': no such column; name the thermal-error column. The columns are: "
            + ", ".join(map(str, run.frame.columns))
        )
    if not tables.source_names:
        return run
    columns = []
    for r, name in enumerate(tables.raw_names[tables.n_measured :], start=tables.n_measured):
        if name not in run.frame.columns:
            available = ", ".join(map(str, run.frame.columns))
            uses = " and ".join(tables.uses_of(r))
            raise InputError(
                f"{run.source}: column '{name}' not found; the model reads it ({uses}). The columns are: {available}"
            )
        values = numeric_column(run.frame, name, run.source, allow_nonfinite=True)
        columns.append(values * millimetres_per_unit(name) if name == tables.position_name else values)
    readings = np.column_stack([run.temps, *columns])
    in_mm = position_unit_notes(tables.position_name, run.source) if tables.has_position else ()
    return dataclasses.replace(run, temps=readings, temp_names=tables.raw_names, notes=run.notes + in_mm)


@dataclass(frozen=True)
class SavedState:
    """The rule's state at the end of a modelling file that is not at hand: where, after how many samples, and the
    reading its error was taken from (``COLUMN-start``; None: the error is read as logged)."""

    path: str
    samples: int
    state: Mapping[str, Any]
    error_zero_um: float | None = None


def earlier_recordings(
    args: argparse.Namespace, model: ModelFile, run: Run, load
) -> tuple[list, list, str | None, SavedState | None]:
    """The files replayed before ``run`` (``--continues``, else the modelling file it continues), their readings
    (``load(path)``), the note on a modelling file found by its clock or first row (None: none was), and the
    rule's saved state at that file's end when the file is not at hand (module docstring)."""
    if args.continues and args.fresh:
        raise InputError("--fresh and --continues: give one of them (--fresh starts the rule afresh)")
    refuse_repeated([*(args.continues or []), args.data], "to replay (--data, --continues)")
    if args.continues or args.fresh:
        return list(args.continues or []), [load(path) for path in args.continues or []], None, None
    found, note, entry = continued_recording(model.training, run, args.model)
    if found is None:
        if entry is None:
            return [], [], note, None
        precision = getattr(args, "precision", "double")
        k = list(model.training[RECORDINGS_KEY]).index(entry)
        saved = entry[END_STATE]
        where = f"{args.model}: training.recordings[{k}].{END_STATE}.{precision}"
        rule = SwitchingRule(model, precision=precision, period_s=run.period)
        restore(rule, saved[precision], where)  # a state that does not fit the rule is refused, named by its key
        return [], [], note, SavedState(entry["path"], int(saved["samples"]), saved[precision], entry.get(ZERO_KEY))
    try:
        history = load(found)
    except InputError as exc:
        reason = str(exc).split("; ")[0].removeprefix(f"{found}: ")
        return (
            [],
            [],
            (
                f"{run.name} looks like the rest of the modelling recording {found}, which is not read as one run here "
                f"({reason}): the rule starts afresh; give the part before this run with --continues FILE"
            ),
            None,
        )
    difference = recording_difference(history, run, ignore=probe_columns(args.probe_column))
    if difference is not None:
        return (
            [],
            [],
            f"{run.name} looks like the rest of the modelling recording {found}, but {difference}: the rule "
            "starts afresh",
            None,
        )
    return [found], [history], note, None


def end_states(model: ModelFile, entry: Mapping[str, Any], clock: Mapping[str, Any]) -> dict[str, Any] | None:
    """``{"samples": N, "double": state, "single": state}``: the rule's state after the modelling file of
    ``entry`` replayed alone from the start, in both precisions (None when the file is not read here as the
    rule reads a run, or not on the clock the entry recorded). ``clock``: how the fit read the file's clock
    (``--period-tolerance``, ``--resample``)."""
    tables = RuleTables.from_model(model)
    try:
        error = model.error or "error_um"
        run = load_readings(entry["path"], tables, time=time_column(model), error=error, **clock)
    except InputError:
        return None
    if not (run.time[0] == entry["first_time_s"] and run.time[-1] == entry["last_time_s"]):
        return None
    states: dict[str, Any] = {"samples": int(run.n_samples)}
    for precision in PRECISIONS:
        try:
            rule = SwitchingRule(model, precision=precision, period_s=run.period)
        except InputError:  # read on another period than the model's
            return None
        rule.replay(run.temps)
        states[precision] = capture(rule)
    return states


def with_end_states(model: ModelFile, clock: Mapping[str, Any]) -> ModelFile:
    """``model`` with the rule's state at the end of each modelling file it records (``end_state``), so that
    ``replay`` can go on from it when the file is gone; ``clock`` as :func:`end_states` takes it."""
    training = dict(model.training or {})
    entries = training.get(RECORDINGS_KEY) or []
    if not entries:
        return model
    updated = []
    for entry in entries:
        states = end_states(model, entry, clock)
        updated.append({**entry, **({END_STATE: states} if states is not None else {})})
    return model.replace(training={**training, RECORDINGS_KEY: updated})


__all__ = ["PRECISIONS", "SavedState", "earlier_recordings", "load_readings", "with_end_states"]
