"""The modelling recordings a model file remembers, and the one a replayed run continues.

A long test is often cut in two: the model is fitted on the first part and
replayed on the rest. On the controller the rule runs on through the cut; the
rest replayed alone starts it afresh (a heat law from rest, group 1), a fault
the controller does not have. ``fit`` and ``diagnose`` record in the model
file's ``training.recordings`` where each modelling file is, its SHA-256 and
where its clock ends. ``replay`` of a run whose clock picks up one sampling
period after such a recording ends replays that file first, as ``--continues
FILE`` does, when it is still there with the same contents, and from the
rule's state at that file's end, which the entry keeps, when it is not
(:mod:`groupfit.commands.replay_readings`; ``--fresh``: start afresh all the
same). A file whose time stamps are dates starts its clock at
0 (:func:`groupfit.readtable.datetimes_to_seconds`) and keeps the date-time of
its first row (``clock_origin_s``, seconds since 1970, in the clock of its last
row; ``clock_shift_s``, where a local clock without a UTC offset changed to or
from summer time, what that moved its first row by): the next file of a
logger that rolls its files is told by its date-times, its first row's in the
clock of that row. A file whose clock
starts again is told by its first row (:mod:`groupfit.pickup`), against the
recording's last row kept in the entry.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from groupfit.continuation import clock_runs_on, zero_of
from groupfit.data import PERIOD_TOLERANCE, Run
from groupfit.error_start import ZERO_KEY
from groupfit.io import file_sha256
from groupfit.pickup import clock_starts_again, end_row, picks_up
from groupfit.readtable import CLOCK_ORIGIN
from groupfit.training_checks import CLOCK_SHIFT, END_STATE, LAST_READINGS, PICKUP_LIMIT, READING_STEPS, RECORDINGS_KEY


def recording_entries(paths: Sequence[Any], runs: Sequence[Run], model_dir: str | Path | None = None) -> list[dict]:
    """One entry per modelling file read from a path: its absolute path (and its path from ``model_dir``, the
    model file's folder, so that a folder moved whole keeps them together), digest and clock.

    ``runs`` are the runs read from ``paths`` in order (a log split at its gaps
    gives several; the clock of a file is that of its first and last run).
    Files that cannot be told apart by path (a data frame, a split whose runs
    cannot be matched to their files) give no entry.
    """
    files = [Path(p) for p in paths if isinstance(p, (str, Path))]
    if not files or len(files) != len(paths) or not runs:
        return []
    if len(files) == 1:
        parts = [list(runs)]
    elif len(files) == len(runs):
        parts = [[run] for run in runs]
    else:
        return []
    entries = []
    for path, own in zip(files, parts):
        if not path.is_file():
            continue
        entry = {
            "path": str(path.resolve()),
            "sha256": file_sha256(path),
            "first_time_s": float(own[0].time[0]),
            "last_time_s": float(own[-1].time[-1]),
            "period_s": float(own[-1].period),
        }
        if own[0].clock_origin_s is not None:
            entry[CLOCK_ORIGIN] = float(own[0].clock_origin_s)
            if own[0].clock_shift_s is not None:
                entry[CLOCK_SHIFT] = float(own[0].clock_shift_s)
        zero = zero_of(own[-1])  # the part a next file goes on from
        if zero is not None:
            entry[ZERO_KEY] = zero
        last, steps, limit = end_row(own[-1])
        if np.isfinite(limit):
            entry.update({LAST_READINGS: last, READING_STEPS: steps, PICKUP_LIMIT: limit})
        if model_dir is not None:
            entry["path_from_model"] = Path(os.path.relpath(path.resolve(), Path(model_dir).resolve())).as_posix()
        entries.append(entry)
    return entries


def overlap_note(training: Mapping[str, Any] | None, run: Run) -> str | None:
    """A note when ``run``'s clock starts inside a modelling file's (the same clock origin): the two overlap, and
    rows the model was fitted on would be scored as a next run's; None otherwise. The origins are compared in the
    clock of each file's first row, so that either may cross a change to or from summer time."""
    for entry in (training or {}).get(RECORDINGS_KEY) or []:
        if _first_origin(entry) != run.first_clock_origin_s or "first_time_s" not in entry:
            continue
        if entry["first_time_s"] <= float(run.time[0]) < entry["last_time_s"]:
            return (
                f"{run.name}'s clock starts at {run.time[0]:g} s, inside the modelling file {Path(entry['path']).name} "
                f"({entry['first_time_s']:g} to {entry['last_time_s']:g} s): the two overlap, and the rows they share "
                "were fitted on; drop them from this file to score it as a next run"
            )
    return None


def _continued_by(entry: Mapping[str, Any], run: Run) -> str | None:
    """How ``run`` continues the recording of ``entry``: "clock", "readings" (its clock starts again and its first
    row picks up where the recording's last left off, :mod:`groupfit.pickup`), or None."""
    last_origin, first_origin = entry.get(CLOCK_ORIGIN), run.first_clock_origin_s
    first_time = float(run.time[0])
    local = CLOCK_SHIFT in entry and run.clock_shift_s is not None
    if clock_runs_on(
        entry["last_time_s"],
        entry["period_s"],
        first_time,
        last_origin_s=last_origin,
        first_origin_s=first_origin,
        local=local,
    ):
        return "clock"
    if any(key not in entry for key in (LAST_READINGS, READING_STEPS, PICKUP_LIMIT)):
        return None
    if abs(run.period - entry["period_s"]) > PERIOD_TOLERANCE * entry["period_s"]:
        return None
    if not clock_starts_again(entry["last_time_s"], first_time, last_origin_s=last_origin, first_origin_s=first_origin):
        return None
    if picks_up(entry[LAST_READINGS], entry[READING_STEPS], entry[PICKUP_LIMIT], run) and not _same_file(entry, run):
        return "readings"
    return None


def _first_origin(entry: Mapping[str, Any]) -> float | None:
    """The date-time a recording's clock counts from, in the clock of its first row (an entry written before the
    shift was kept: in the clock of its last row)."""
    origin = entry.get(CLOCK_ORIGIN)
    return None if origin is None else origin - entry.get(CLOCK_SHIFT, 0.0)


def _same_file(entry: Mapping[str, Any], run: Run) -> bool:
    """Whether ``run`` was read from the recording's own file."""
    path = Path(str(run.source))
    return path.is_file() and file_sha256(path) == entry["sha256"]


def continued_recording(
    training: Mapping[str, Any] | None, run: Run, model_path: str | Path | None = None
) -> tuple[Path | None, str | None, Mapping[str, Any] | None]:
    """The modelling file ``run`` continues, a note on what was found, and the recording's entry when its kept
    state (``end_state``) is to stand in for a file that is not at hand (otherwise None).

    The run continues a recording when its first time stamp follows the
    recording's last by one sampling period
    (:func:`groupfit.continuation.clock_runs_on`), or when its clock starts
    again and its first row picks up where the recording's last row left off
    (:mod:`groupfit.pickup`; entries written before the last row was kept are
    told by the clock alone). The file is
    looked for where it lies from the model file (``model_path``), then at its
    absolute path, and used only with the recorded SHA-256; otherwise the
    rule's state at the file's end stands in for it, when the entry keeps one
    and ``run`` is sampled on the file's period, and the note says which.
    """
    for entry in (training or {}).get(RECORDINGS_KEY) or []:
        how = _continued_by(entry, run)
        if how is None:
            continue
        continues = (
            f"{run.name}'s clock continues the modelling recording"
            if how == "clock"
            else f"{run.name}'s clock starts again, but its first row picks up where the modelling recording"
        )
        ended = f"(it ended at {_ended(entry)})" if how == "clock" else f"left off (at {_ended(entry)})"
        places = [Path(entry["path"])]
        if model_path is not None and entry.get("path_from_model"):
            places.insert(0, Path(model_path).resolve().parent / entry["path_from_model"])
        present = [p for p in places if p.is_file()]
        path = next((p for p in present if file_sha256(p) == entry["sha256"]), None)
        if path is not None:
            note = (
                f"{continues} {path} {ended}: replayed after it, as --continues does, so that the rule and its "
                "derived inputs carry their history as on the controller; --fresh starts them afresh"
            )
            return path, note, None
        if present:
            found = f"{continues} {present[0]} {ended}, but that file has changed since the fit"
            ask = "give the earlier file with --continues FILE"
        else:
            found = f"{continues} {entry['path']} {ended}, which is no longer there"
            ask = "give the file with --continues FILE to carry its history"
        if END_STATE not in entry:
            return None, f"{found}: the rule starts afresh; {ask}", None
        if abs(run.period - entry["period_s"]) > PERIOD_TOLERANCE * entry["period_s"]:
            return None, f"{found}; this run is sampled on another period: the rule starts afresh", None
        note = (
            f"{found}: replayed from the rule's state at that file's end, kept in the model file "
            f"(training.recordings[].{END_STATE}), as the controller, which ran through, goes on; --fresh starts "
            "afresh"
        )
        return None, note, entry
    return None, None, None


def _ended(entry: Mapping[str, Any]) -> str:
    """Where a recording's clock ended: its last date-time (UTC when the stamps named a zone) or its seconds."""
    origin = entry.get(CLOCK_ORIGIN)
    if origin is None:
        return f"{entry['last_time_s']:g} s"
    return pd.Timestamp(origin + entry["last_time_s"], unit="s").isoformat(sep=" ")


def is_modelling_file(training: Mapping[str, Any] | None, path: Any) -> bool:
    """Whether the file at ``path`` is one the model was fitted on (its SHA-256 among ``training.recordings``)."""
    entries = (training or {}).get(RECORDINGS_KEY) or []
    if not entries or not isinstance(path, (str, Path)) or not Path(path).is_file():
        return False
    digest = file_sha256(path)
    return any(entry.get("sha256") == digest for entry in entries)


__all__ = ["RECORDINGS_KEY", "continued_recording", "is_modelling_file", "recording_entries"]
