"""A log whose clock starts again, told by its readings to be the rest of an earlier one.

Many loggers start every file's clock at 0, and a long test cut in two is
often handed over with the rest's time stamps counted from its own start. The
clock then cannot tell a continuation from a new run, but the readings can: a
machine logged on without a pause starts the next file where the last one left
off, its first row as close to the earlier file's last as the earlier file's
last rows are to each other, while a new run (after a night, a cool-down, a
pause of some minutes) starts farther away. The distance of two rows is the
mean over the input temperatures and the error of their difference, each in
units of the column's typical change from one sample to the next (its median
over the earlier run). A run *picks up* an earlier one when its clock does not
go on from the earlier's (it starts again, or one of the two is stamped with
dates and the other not) and the distance of its first row from the earlier's
last is within :data:`LOCAL_MARGIN` times the largest distance between two rows
in a row among the earlier run's last :data:`LOCAL_ROWS`. Two logs stamped with
dates are told by their date-times alone, and a clock that goes on after a gap
is a gap, whatever the readings.

The last rows, not the whole run, set the limit: a speed step moves every
temperature at once, and a limit drawn from the whole run let a file that
started 50 min after a steady stretch pass for its continuation. Measured on
801 cuts of the test data sets, three simulated spindle runs and the shared
measured test: 800 continuations were taken (one missed, at an HVAC step); a
file started after a pause of 5, 20 and 60 samples was taken on 71 %, 29 % and
16 % of the cuts (where the readings barely moved over the pause); another run's first row on 2 of 3671 cuts (cut
early in a cold start, at a state the other run also starts from).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from groupfit.data import Run

LOCAL_ROWS = 60
"""How many of the earlier run's last rows set how far the next file's first row may be from its last."""
LOCAL_MARGIN = 1.5
"""The next file's first row may be this many times farther from the last row than two of the last rows in a
row are at most."""


def reading_columns(run: Run) -> list[str]:
    """The columns a pick-up is told by: the run's inputs and its error, as logged."""
    names = [name for name in run.temp_names if name in run.frame.columns]
    if run.error_name is not None and run.error_name in run.frame.columns and run.error_name not in names:
        names.append(run.error_name)
    return names


def _values(run: Run, column: str) -> np.ndarray:
    return np.asarray(run.frame[column].to_numpy(), dtype=float)


def _row(run: Run, index: int) -> dict[str, float]:
    return {column: float(_values(run, column)[index]) for column in reading_columns(run)}


def last_readings(run: Run) -> dict[str, float]:
    """The run's last row on :func:`reading_columns` (the readings that are numbers)."""
    return {column: value for column, value in _row(run, -1).items() if np.isfinite(value)}


def reading_steps(run: Run) -> dict[str, float]:
    """Per column of :func:`reading_columns`: its typical change from one sample to the next (the median of its
    absolute changes; their mean for a column that changes on fewer than half of the samples, 0 for one that
    never changes). Columns with fewer than two readings in a row are left out."""
    steps = {}
    for column in reading_columns(run):
        change = np.abs(np.diff(_values(run, column)))
        change = change[np.isfinite(change)]
        if change.size:
            median = float(np.median(change))
            steps[column] = median if median > 0 else float(change.mean())
    return steps


def distance(first: Mapping[str, float], last: Mapping[str, float], steps: Mapping[str, float]) -> float:
    """The distance of two rows: the mean over the columns both hold of their difference in units of the column's
    typical change (``steps``); a column that never changed counts as infinitely far if it differs. NaN when
    they share no column."""
    terms, compared = [], 0
    for column, value in first.items():
        if column not in last or column not in steps or not np.isfinite(value):
            continue
        compared += 1
        difference = abs(value - last[column])
        if steps[column] > 0:
            terms.append(difference / steps[column])
        elif difference > 1e-9 * max(1.0, abs(last[column])):
            return np.inf
    if not compared:
        return float("nan")
    return float(np.mean(terms)) if terms else 0.0


def pickup_limit(run: Run, steps: Mapping[str, float]) -> float:
    """How far a next file's first row may be from the run's last row: :data:`LOCAL_MARGIN` times the largest
    :func:`distance` between two rows in a row among its last :data:`LOCAL_ROWS` (NaN when none share a
    reading)."""
    columns = [column for column in reading_columns(run) if steps.get(column, 0.0) > 0]
    if not columns:
        return float("nan")
    rows = np.column_stack([_values(run, c) for c in columns])[-(LOCAL_ROWS + 1) :]
    scaled = np.abs(np.diff(rows, axis=0)) / np.array([steps[c] for c in columns])
    counted = np.isfinite(scaled).sum(axis=1)
    if not counted.any():
        return float("nan")
    mean = np.where(np.isfinite(scaled), scaled, 0.0).sum(axis=1)[counted > 0] / counted[counted > 0]
    return float(LOCAL_MARGIN * mean.max())


def clock_starts_again(
    last_time_s: float, first_time_s: float, *, last_origin_s: float | None, first_origin_s: float | None
) -> bool:
    """Whether a run's clock does not go on from an earlier run's: it starts at or before the earlier's last time
    stamp, or only one of the two is stamped with dates. Two dated logs are placed by their date-times."""
    if last_origin_s is not None and first_origin_s is not None:
        return False
    if (last_origin_s is None) != (first_origin_s is None):
        return True
    return first_time_s <= last_time_s


def first_readings(run: Run) -> dict[str, float]:
    """The run's first row on :func:`reading_columns`."""
    return _row(run, 0)


def end_row(run: Run) -> tuple[dict[str, float], dict[str, float], float]:
    """What a next file's first row is compared with: the run's :func:`last_readings`, :func:`reading_steps` and
    :func:`pickup_limit`."""
    steps = reading_steps(run)
    return last_readings(run), steps, pickup_limit(run, steps)


def picks_up(last: Mapping[str, float], steps: Mapping[str, float], limit: float, run: Run) -> bool:
    """Whether ``run``'s first row is within ``limit`` (:func:`distance`) of an earlier run's last row, compared
    on one of ``run``'s input temperatures or more."""
    first = first_readings(run)
    if not any(name in last and np.isfinite(first.get(name, np.nan)) for name in run.temp_names):
        return False
    found = distance(first, last, steps)
    return bool(np.isfinite(found) and np.isfinite(limit) and found <= limit)


def run_picks_up(previous: Run, run: Run) -> bool:
    """Whether ``run`` picks up where ``previous`` left off (module docstring); the columns and period are
    :func:`groupfit.continuation.same_recording`'s to check."""
    if not clock_starts_again(
        previous.time[-1],
        run.time[0],
        last_origin_s=previous.clock_origin_s,
        first_origin_s=run.first_clock_origin_s,
    ):
        return False
    return picks_up(*end_row(previous), run)


__all__ = [
    "LOCAL_MARGIN",
    "LOCAL_ROWS",
    "clock_starts_again",
    "distance",
    "end_row",
    "first_readings",
    "last_readings",
    "pickup_limit",
    "picks_up",
    "reading_columns",
    "reading_steps",
    "run_picks_up",
]
