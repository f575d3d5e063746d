"""A run that continues another: the controller's history carried into it.

Shops split long logs into files, and a run held back for validation is often
the rest of the modelling log. A low-pass of the spindle speed evaluated on
the validation file alone starts from rest at its first row, while the
machine is hot, and the run-time rule starts again at group 1: faults the
controller, which ran through, does not have. When a run's first time stamp
follows another's last by one sampling period, the two are one recording: the
later run is judged with the earlier in front of it, its error left out, so
that the derived inputs, a reference taken at the start and the run-time
switching carry their history into it. Only the later run's rows are scored.
A log split into more files chains. ``diagnose``, ``replay`` and ``compare``
use this; ``--continues`` takes a run as the rest of the one before it whatever
its time stamps. An error read from the run's start (``--error COLUMN-start``,
:mod:`groupfit.error_start`) is read in the rest from the recording's start
(:func:`picked_up`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.clock_changes import change_between
from groupfit.data import PERIOD_TOLERANCE, Run
from groupfit.default_columns import length_unit
from groupfit.error_start import is_from_start
from groupfit.errors import InputError
from groupfit.features import Feature
from groupfit.pickup import run_picks_up

CONTIGUITY_TOLERANCE = 0.5
"""The gap between the two runs may differ from one sampling period by this share of it."""


def recording_difference(previous: Run, run: Run, *, ignore: Sequence[str] = ()) -> str | None:
    """What keeps ``run`` from being the rest of ``previous``'s recording — its time column, inputs, columns,
    error column or period differ — in words that name it; None when nothing does. ``ignore``: columns either
    part may log alone (a probe's readings)."""
    if previous.time_name != run.time_name:
        return f"its time column is '{run.time_name}', not '{previous.time_name}'"
    if previous.temp_names != run.temp_names:
        return f"its inputs are {', '.join(run.temp_names)}, not {', '.join(previous.temp_names)}"
    added = [str(c) for c in run.frame.columns if c not in previous.frame.columns and c not in ignore]
    lost = [str(c) for c in previous.frame.columns if c not in run.frame.columns and c not in ignore]
    if added or lost:
        parts = [f"adds {', '.join(added)}" if added else "", f"lacks {', '.join(lost)}" if lost else ""]
        return f"its columns differ (it {' and '.join(p for p in parts if p)}: log both parts alike)"
    if previous.error_name != run.error_name:
        return f"its error column is '{run.error_name}', not '{previous.error_name}'"
    if abs(previous.period - run.period) > PERIOD_TOLERANCE * previous.period:
        return f"it is sampled every {run.period:g} s, not every {previous.period:g} s"
    return None


def same_recording(previous: Run, run: Run, *, ignore: Sequence[str] = ()) -> bool:
    """Whether ``run`` could be the rest of ``previous``'s recording (:func:`recording_difference`)."""
    return recording_difference(previous, run, ignore=ignore) is None


def clock_runs_on(
    last_time_s: float,
    period_s: float,
    first_time_s: float,
    *,
    last_origin_s: float | None = None,
    first_origin_s: float | None = None,
    local: bool = False,
) -> bool:
    """Whether a clock that ended at ``last_time_s`` picks up at ``first_time_s`` one sampling period later.

    ``*_origin_s``: the date-time each clock counts from, the earlier file's in the clock of its last row
    (:attr:`groupfit.data.Run.clock_origin_s`), the later file's in the clock of its first row
    (:attr:`~groupfit.data.Run.first_clock_origin_s`), so that either file may cross a change to or from summer
    time; two logs stamped with dates are compared by their date-times, a dated log never goes on from one on a
    clock of its own (or the other way round). ``local``: both are stamped in local wall-clock time without a UTC
    offset, and a file cut where the clock went ahead or back an hour goes on from the one before it
    (:func:`groupfit.clock_changes.change_between`).
    """
    if (last_origin_s is None) != (first_origin_s is None):
        return False
    last, first = last_time_s + (last_origin_s or 0.0), first_time_s + (first_origin_s or 0.0)
    spare = CONTIGUITY_TOLERANCE * period_s
    if abs(first - last - period_s) <= spare:
        return True
    return bool(local and last_origin_s is not None and change_between(last, first, period_s, spare))


def clock_continues(previous: Run, run: Run) -> bool:
    """Whether ``run``'s clock picks up one sampling period after ``previous``'s ends (two logs stamped with dates:
    by their date-times, ``previous``'s last in the clock of its last row, ``run``'s first in the clock of its
    first row, each file's clock counting from its first row)."""
    return clock_runs_on(
        previous.time[-1],
        previous.period,
        run.time[0],
        last_origin_s=previous.clock_origin_s,
        first_origin_s=run.first_clock_origin_s,
        local=previous.clock_shift_s is not None and run.clock_shift_s is not None,
    )


def continues(previous: Run, run: Run, *, ignore: Sequence[str] = ()) -> bool:
    """Whether ``run`` is the rest of ``previous``'s recording: the same columns and period, and either its clock
    goes on one sampling period after ``previous`` ends or, on a clock started again, its first row picks up
    where ``previous``'s last left off (:mod:`groupfit.pickup`). ``ignore``: as :func:`recording_difference`."""
    if not same_recording(previous, run, ignore=ignore):
        return False
    return clock_continues(previous, run) or run_picks_up(previous, run)


def restamped(run: Run, previous: Run) -> Run:
    """``run`` with its time stamps going on one sampling period after ``previous``'s last (on its clock).

    Its first row then keeps the clock ``previous``'s last row kept, and a local clock's changes of its own
    (:attr:`~groupfit.data.Run.clock_shift_s`) still move its last row's clock from there, so that a file going
    on from its last row is told as one going on from it unrestamped would be.
    """
    time = run.time - run.time[0] + previous.time[-1] + previous.period
    frame = run.frame.copy()
    frame[run.time_name] = time
    origin, shift = previous.clock_origin_s, previous.clock_shift_s
    if origin is not None and shift is not None:  # a local clock: the run's own changes go on from previous's
        shift = run.clock_shift_s or 0.0
        origin += shift
    return replace(run, time=time, frame=frame, clock_origin_s=origin, clock_shift_s=shift)


def logged_error(run: Run) -> np.ndarray:
    """The run's error as logged (µm, scaled by its name, not taken from its start)."""
    values = pd.to_numeric(run.frame[run.error_name], errors="coerce").to_numpy(dtype=float)
    return values * length_unit(run.error_name)[1]


def zero_of(run: Run) -> float | None:
    """The reading (µm, as logged) the run's error is taken from; None when it is not read from a start
    (``COLUMN-start``)."""
    if run.error is None or not is_from_start(run.error_name) or run.error_name not in run.frame.columns:
        return None
    logged = logged_error(run)
    if logged.shape != run.error.shape:
        return None
    both = np.isfinite(logged) & np.isfinite(run.error)
    return float(np.median(logged[both] - run.error[both])) if both.any() else None


def picked_up(run: Run, zero: float | None) -> Run:
    """``run`` with its error taken from ``zero`` (µm, as logged: the first reading of the recording it is the
    rest of) instead of from its own first reading; itself when its error is not read from a start."""
    own = zero_of(run)
    if zero is None or own is None:
        return run
    return replace(run, error=run.error + (own - zero))


def preceding_run(run: Run, candidates: Sequence[Run], *, ignore: Sequence[str] = ()) -> Run | None:
    """The run among ``candidates`` that ``run`` continues, if any."""
    return next((previous for previous in candidates if continues(previous, run, ignore=ignore)), None)


def with_history(run: Run, history: Run | None) -> tuple[Run, int]:
    """``run`` with ``history`` in front of it, the history's error left empty; and the rows put in front."""
    if history is None:
        return run, 0
    frame = pd.concat([history.frame, run.frame], ignore_index=True)
    if run.error_name is not None:
        frame.loc[: len(history.frame) - 1, run.error_name] = np.nan
    error = None if run.error is None else np.concatenate([np.full(len(history.time), np.nan), run.error])
    joined = replace(
        run,
        time=np.concatenate([history.time, run.time]),
        temps=np.vstack([history.temps, run.temps]),
        error=error,
        frame=frame,
    )
    return joined, len(history.time)


def with_histories(
    runs: Sequence[Run], earlier: Sequence[Run], *, assume_continued: bool = False, ignore: Sequence[str] = ()
) -> tuple[list[Run], list[int], list[str]]:
    """Each of ``runs`` with what it continues in front; the rows put in front of each; a note for each.

    A run continues one of ``earlier`` or one of ``runs`` before it (which
    then brings its own history along). With ``assume_continued`` each run
    is taken to continue the one before it (the first, the last of
    ``earlier``) whatever its time stamps (a file whose clock starts again),
    when the two share columns, inputs and period; its time stamps are then
    taken to go on from that run's. ``ignore``: columns either part may log alone (a probe's readings).
    """
    joined_of = {id(run): run for run in earlier}  # each run, with its history in front
    candidates = list(earlier)
    joined, skipped, notes = [], [], []
    for run in runs:
        history = preceding_run(run, candidates, ignore=ignore)
        if history is None and assume_continued and candidates:
            history = candidates[-1]
            difference = recording_difference(history, run, ignore=ignore)
            if difference is not None:
                raise InputError(
                    f"{run.source}: --continues, but it cannot be the rest of {history.name}: {difference}; "
                    "leave --continues out for a separate run"
                )
            run = picked_up(restamped(run, history), zero_of(history))
            notes.append(
                f"{run.name} is taken to continue {history.name} (--continues), whatever its time stamps: judged "
                f"with {history.name} in front, so that its derived inputs and run-time state carry their "
                "history, as on the controller"
            )
            history = joined_of[id(history)]
        elif history is not None:
            run = picked_up(run, zero_of(history))
            if clock_continues(history, run):
                how = "its first time stamp one sampling period after the last"
            else:
                how = f"its clock starts again, but its first row picks up where {history.name}'s last left off"
                run = restamped(run, history)
            notes.append(
                f"{run.name} continues {history.name} ({how}): judged with {history.name} in front, so that its "
                "derived inputs and run-time state carry their history, as on the controller"
            )
            history = joined_of[id(history)]
        run_with_history, rows = with_history(run, history)
        joined.append(run_with_history)
        skipped.append(rows)
        joined_of[id(run)] = run_with_history
        candidates.append(run)
    return joined, skipped, notes


COLD_START_NOTE = "starts with a source on,"
"""What a note on a validation run that starts hot without its history says (the report puts it first)."""


def started_running_notes(
    runs: Sequence[Run], skipped: Sequence[int], features: Sequence[Feature], lag_of: str = "the effect's"
) -> list[str]:
    """A note for each run that starts with a source on, carries no history, and has a lag of it (``lag_of``:
    whose lag the note names).

    A lag from rest (``start="rest"``) takes the source as off before the run, as after a controller restart.
    A file cut from a longer recording, whose time stamps start again, starts hot instead: the lag starts
    cold there, and the validation of the effect is pessimistic for its first time constants.
    """
    notes = []
    for run, rows in zip(runs, skipped):
        if rows:  # judged with its history in front
            continue
        for feature in features:
            if feature.start != "rest" or feature.column not in run.frame.columns:
                continue
            first = pd.to_numeric(run.frame[feature.column], errors="coerce").to_numpy(dtype=float)[0]
            if np.isfinite(first) and first != 0.0:
                lag = feature.describe().replace(", from rest", "")
                notes.append(
                    f"{run.name} {COLD_START_NOTE} {feature.column} = {first:g}, and is not the continuation of "
                    f"a modelling run: {lag_of} {lag} starts there from rest (the source off before the "
                    "file), as after a controller restart; if the file is the rest of the modelling recording, "
                    "keep its time stamps going on from the modelling run's (one sampling period after its last), "
                    "or say so with --continues, and it is judged with that history"
                )
    return notes
