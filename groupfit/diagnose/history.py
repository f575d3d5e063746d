"""A run that continues another: the controller's history carried into it.

Shops split long logs into files, and a run held back for validation is often
the rest of the modelling log. A low-pass of the spindle speed evaluated on
the validation file alone starts from rest at its first row, while the
machine is hot: the derived inputs are wrong for the first time constants of
the run, a fault the controller, which ran through, does not have. When a
validation run's first time stamp follows a modelling run's last by one
sampling period, or its clock starts again at a first row that picks up where
the modelling run's last left off (:mod:`groupfit.pickup`), the two are one
recording: the validation run is judged
with the modelling run in front of it, its error left out, so that the
derived inputs, a reference taken at the start and the run-time switching
carry their history into it. Only the validation rows are scored. A log
split into more files chains: a validation run that continues another is
judged with all that came before it. Modelling runs that continue one another
are chained the same way (each fitted and scored on its own rows, with the
rows before it in front): their derived inputs are those of the whole log.
"""

from __future__ import annotations

from groupfit.continuation import (
    COLD_START_NOTE,
    continues,
    preceding_run,
    restamped,
    same_recording,
    started_running_notes,
    with_histories,
    with_history,
)

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
