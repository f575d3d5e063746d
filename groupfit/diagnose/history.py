"""A run that continues another: the controller's history carried into it.

Shops split long logs into files, and a run held back for validation is often
the rest of the modelling log. A low-pass of the spindle speed evaluated on
the validation file alone starts from rest at its first row, while the
machine is hot: the derived inputs are wrong for the first time constants of
the run, a fault the controller, which ran through, does not have. When a
validation run's first time stamp follows a modelling run's last by one
sampling period, the two are one recording: the validation run is judged
with the modelling run in front of it, its error left out, so that the
derived inputs, a reference taken at the start and the run-time switching
carry their history into it. Only the validation rows are scored. A log
split into more files chains: a validation run that continues another is
judged with all that came before it. Modelling runs that continue one another
are chained the same way (each fitted and scored on its own rows, with the
rows before it in front): their derived inputs are those of the whole log.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.continuation import continues, preceding_run, restamped, same_recording, with_histories, with_history
from groupfit.data import Run
from groupfit.features import Feature

__all__ = [
    "COLD_START_NOTE",
    "continues",
    "preceding_run",
    "restamped",
    "same_recording",
    "started_running_notes",
    "with_histories",
    "with_history",
]

COLD_START_NOTE = "starts with a source on,"
"""What a note on a validation run that starts hot without its history says (the report puts it first)."""


def started_running_notes(runs: Sequence[Run], skipped: Sequence[int], features: Sequence[Feature]) -> list[str]:
    """A note for each validation run that starts with a source on, carries no history, and has a lag of it.

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
                    f"a modelling run: the effect's {lag} starts there from rest (the source off before the "
                    "file), as after a controller restart; if the file is the rest of the modelling recording, "
                    "keep its time stamps going on from the modelling run's (one sampling period after its last), "
                    "or say so with --continues, and it is judged with that history"
                )
    return notes
