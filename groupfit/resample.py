"""Resampling a log onto a uniform period: several readings per period averaged, gaps split.

Loggers rarely write one row per period: a 3-D printer homes its probe three
times 4 s apart once a minute, a data logger writes whenever a value changes.
:func:`resample_frame` bins the rows into periods of ``period_s`` seconds and
takes the mean of every numeric column over the rows of a bin (non-finite
cells left out), the bin's centre as its time. The bins are placed so that the
readings sit in their middle: their edges lie half a period away from the
circular mean of the readings' phases (a log whose readings come in bursts
keeps each burst in one bin, whatever the clock's offset).

A period without a reading is an *empty* bin. Missed readings are counted
in the log's own cycles: one cycle is one period, or, for a period shorter
than the log's (a 60 s log resampled to 20 s), the log's typical step between
occupied periods. A run of empty bins that misses at most
:data:`GAP_PERIODS` of the log's cycles is filled by linear interpolation
between the bins around it (a missed cycle); a longer run is a *gap*: the log
is split there into separate runs, never bridged by made-up samples. A column
read in none of the rows of a period (an empty cell: one sensor missed a
reading) is interpolated the same way when it misses at most
:data:`GAP_PERIODS` periods with readings in a row between two readings of
its own (the empty bins among them with it); a longer silence stays empty,
and the loader names its first row. At either end of a stretch, the periods
before a column's first reading or after its last (records of several kinds
that start and stop at other times: a temperature record every 20 s among
probe readings every 2 s) are dropped when at most :data:`GAP_PERIODS` of
them hold readings; the measured columns, which may be read on some periods
alone, do not count. Each piece keeps, under :data:`LOG_READINGS` in its
``attrs``, how many of the log's rows each of its periods holds, so that a
refusal of a sensor's longer silence counts the readings the log missed, and, under
:data:`LOG_ROWS`, the log's row each period starts at, so that it names the log's rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from groupfit.errors import InputError
from groupfit.interleaved import refuse_interleaved, stamp_groups
from groupfit.readtable import empty_cells
from groupfit.timestamps import clock_restart, refuse_clock_change, restart_refusal

GAP_PERIODS = 3
"""More empty periods in a row than this split the log into runs; fewer are interpolated."""
LOG_READINGS = "groupfit.log_readings"
"""The ``attrs`` key of a resampled piece: for each of its rows (periods), the number of the log's rows binned
into it (0: an empty period), so that a refusal counts the readings the log missed, not the periods."""
LOG_ROWS = "groupfit.log_rows"
"""The ``attrs`` key of a resampled piece: for each of its rows (periods) and one past its last, the position in
the log of the first row binned into that period or later (the log's rows ``LOG_ROWS[i]`` to
``LOG_ROWS[i + 1] - 1`` fall into period ``i``)."""
MAX_RESAMPLED_ROWS = 5_000_000
"""The most rows a resampled run may have (a period far below the log's would fill the memory with empty rows)."""


@dataclass(frozen=True)
class Resampled:
    """A log binned into periods."""

    pieces: list[pd.DataFrame]
    """The binned tables, one per stretch between gaps, the time column holding the bins' centres."""
    combined: int
    """Readings (rows of the log) averaged into the bins."""
    empty: int
    """Empty bins filled by interpolation (a gap's bins are not counted)."""
    gaps: list[tuple[float, float]]
    """Each gap that split the log: the time of the last reading before it and of the first after it (s)."""
    missed: int = 0
    """Missed readings of a column (a period with readings, none of that column) filled by interpolation."""
    trimmed: int = 0
    """Periods dropped at the ends of stretches, before a column's first reading or after its last."""

    def note(self, label: str, period_s: float, n_bins: int) -> str:
        """The line a verb prints about the resampling."""
        text = (
            f"{label}: resampled to {period_s:g} s: {self.combined} reading(s) averaged into {n_bins} period(s), "
            f"{self.empty} empty period(s) interpolated"
        )
        if self.missed:
            text += f", {self.missed} missed reading(s) of a column interpolated"
        if self.trimmed:
            text += f", {self.trimmed} period(s) at the ends without a reading of every column dropped"
        if self.gaps:
            where = ", ".join(f"{a:g} s to {b:g} s" for a, b in self.gaps)
            text += (
                f"; split into {len(self.pieces)} runs at {len(self.gaps)} gap(s) of more than {GAP_PERIODS} "
                f"missed cycles ({where})"
            )
        return text


def bin_phase(time: np.ndarray, period_s: float) -> float:
    """Where the bins start (s, in ``[0, period)``): half a period from the readings' circular mean phase."""
    angle = 2.0 * np.pi * np.mod(time - time[0], period_s) / period_s
    mean = np.arctan2(np.mean(np.sin(angle)), np.mean(np.cos(angle)))
    centre = (mean / (2.0 * np.pi)) * period_s
    return float(np.mod(time[0] + centre - 0.5 * period_s, period_s))


def resample_frame(
    frame: pd.DataFrame, *, time: str, period_s: float, label: str, measured: tuple[str, ...] = ()
) -> Resampled:
    """Bin ``frame`` into periods of ``period_s`` seconds (see the module).

    Parameters
    ----------
    frame : DataFrame
        The log as read; ``time`` must be numeric, finite and increasing
        (ties are allowed: several readings with one time stamp).
    time : str
        The time column (s).
    period_s : float
        The period to resample to (s), > 0.
    label : str
        The source, for messages.
    measured : tuple of str
        Columns whose missed readings are never filled (the thermal error:
        a period without one was not measured).

    Returns
    -------
    Resampled
        Numeric columns only: a column of text is left out; one without any reading (a channel not
        connected) stays, empty, for the loader to name.
    """
    if not (np.isfinite(period_s) and period_s > 0):
        raise InputError(f"--resample {period_s!r}: give the period in seconds, a number > 0")
    stamps = pd.to_numeric(frame[time], errors="coerce").to_numpy(dtype=float)
    bad = np.flatnonzero(~np.isfinite(stamps))
    if bad.size:
        row = int(bad[0])
        raise InputError(f"{label}: row {row + 1}, column '{time}': {frame[time].iloc[row]!r} is not a time in s")
    refuse_clock_change(stamps, label, time)
    back = np.flatnonzero(np.diff(stamps) < 0)
    if back.size and clock_restart(stamps) is not None:
        raise restart_refusal(stamps, int(back[0]) + 1, label, time, resampling=True)
    if back.size:
        i = int(back[0]) + 1
        raise InputError(
            f"{label}: column '{time}' goes back at row {i + 1} ({stamps[i]:g} s after {stamps[i - 1]:g} s); "
            "sort the rows by time before resampling"
        )
    numeric = {}
    for column in frame.columns:
        if column == time:
            continue
        values = pd.to_numeric(frame[column], errors="coerce")
        if values.notna().any() or empty_cells(frame[column]).all():
            numeric[column] = values.to_numpy(dtype=float)
    _refuse_too_many_rows(stamps, period_s, label)
    start = stamps[0] - np.mod(stamps[0] - bin_phase(stamps, period_s), period_s)
    index = np.floor((stamps - start) / period_s + 1e-9).astype(np.int64)
    refuse_interleaved(frame, [stamp_groups(stamps), index], time=time, label=label)
    n_bins = int(index[-1]) + 1
    counts = np.bincount(index, minlength=n_bins)
    log_rows = np.searchsorted(index, np.arange(n_bins + 1))
    table = {}
    for column, values in numeric.items():
        finite = np.isfinite(values)
        sums = np.bincount(index[finite], weights=values[finite], minlength=n_bins)
        hits = np.bincount(index[finite], minlength=n_bins)
        with np.errstate(invalid="ignore", divide="ignore"):
            table[column] = np.where(hits > 0, sums / np.maximum(hits, 1), np.nan)
    centres = start + (np.arange(n_bins) + 0.5) * period_s
    occupied = counts > 0
    pieces, gaps, empty, unread, trimmed = [], [], 0, 0, 0
    first = 0
    for stop in _stretch_ends(occupied, _gap_bins(occupied)):
        piece = pd.DataFrame({time: centres[first:stop], **{c: v[first:stop] for c, v in table.items()}})
        filled, missed = _interpolate_empty(piece, occupied[first:stop], time, measured)
        empty += filled
        unread += missed
        piece, lead, tail = _without_ragged_ends(piece, occupied[first:stop], (time, *measured))
        trimmed += lead + tail
        piece.attrs[LOG_READINGS] = tuple(int(c) for c in counts[first + lead : stop - tail])
        piece.attrs[LOG_ROWS] = tuple(int(r) for r in log_rows[first + lead : stop - tail + 1])
        pieces.append(piece)
        following = _next_occupied(occupied, stop)
        if following is not None:
            gaps.append((float(stamps[index == stop - 1][-1]), float(stamps[index == following][0])))
            first = following
    return Resampled(pieces=pieces, combined=int(len(stamps)), empty=empty, gaps=gaps, missed=unread, trimmed=trimmed)


def _refuse_too_many_rows(stamps: np.ndarray, period_s: float, label: str) -> None:
    """Refuse a period that would cut the run into more than :data:`MAX_RESAMPLED_ROWS` rows."""
    rows = (stamps[-1] - stamps[0]) / period_s + 1.0
    if rows > MAX_RESAMPLED_ROWS:
        steps = np.diff(stamps)
        steps = steps[steps > 0]
        typical = f"; the log's own period is about {float(np.median(steps)):.3g} s" if steps.size else ""
        raise InputError(
            f"{label}: --resample {period_s:g} s cuts the run's {stamps[-1] - stamps[0]:g} s into {rows:.3g} rows "
            f"(at most {MAX_RESAMPLED_ROWS:.0e}){typical}: give a longer period"
        )


def _without_ragged_ends(
    piece: pd.DataFrame, occupied: np.ndarray, exempt: tuple[str, ...]
) -> tuple[pd.DataFrame, int, int]:
    """``piece`` without the periods at its ends that come before a column's first reading or after its last,
    where at most :data:`GAP_PERIODS` of them hold readings (a longer silence is left for the loader to name),
    and how many were dropped at its start and at its end. The ``exempt`` columns (the time, the measured
    error, which may be read on some periods alone) do not count."""
    n = len(piece)
    known = np.isfinite(piece.drop(columns=[c for c in exempt if c in piece.columns]).to_numpy(dtype=float))
    read = known.any(axis=0)
    if n <= 2 * GAP_PERIODS + 1 or not read.any():
        return piece, 0, 0
    lead = _silent_end(known[:, read], occupied)
    tail = _silent_end(known[::-1, read], occupied[::-1])
    if not lead + tail:
        return piece, 0, 0
    return piece.iloc[lead : n - tail].reset_index(drop=True), lead, tail


def _silent_end(known: np.ndarray, occupied: np.ndarray) -> int:
    """The most leading bins before a column's first reading among the columns whose silence there spans at
    most :data:`GAP_PERIODS` occupied bins."""
    before = np.concatenate([[0], np.cumsum(occupied)])
    leads = np.argmax(known, axis=0)
    return int(max((k for k in leads if before[k] <= GAP_PERIODS), default=0))


def _gap_bins(occupied: np.ndarray) -> int:
    """The most empty bins in a row that are still missed cycles: :data:`GAP_PERIODS` of the log's own cycles,
    whose length in bins is the typical step between occupied bins (1 unless the period is shorter than the
    log's)."""
    steps = np.diff(np.flatnonzero(occupied))
    cycle = max(1, int(round(float(np.median(steps))))) if steps.size else 1
    return (GAP_PERIODS + 1) * cycle - 1


def _stretch_ends(occupied: np.ndarray, gap_bins: int) -> list[int]:
    """End (exclusive) of every stretch of bins between gaps of more than ``gap_bins`` empty bins."""
    ends = []
    k, n = 0, len(occupied)
    while k < n:
        if occupied[k]:
            k += 1
            continue
        run_end = k
        while run_end < n and not occupied[run_end]:
            run_end += 1
        if run_end - k > gap_bins and run_end < n:
            ends.append(k)
        k = run_end
    last = int(np.flatnonzero(occupied)[-1]) + 1
    return [*ends, last]


def _next_occupied(occupied: np.ndarray, stop: int) -> int | None:
    later = np.flatnonzero(occupied[stop:])
    return None if later.size == 0 else stop + int(later[0])


def _interpolate_empty(
    piece: pd.DataFrame, occupied: np.ndarray, time: str, measured: tuple[str, ...]
) -> tuple[int, int]:
    """Fill, in every column, the runs of bins without a reading of it that lie between two of its readings and
    span at most :data:`GAP_PERIODS` occupied bins (a missed reading of one sensor, with the empty bins around
    it); longer runs stay empty. The ``measured`` columns get only runs of empty bins filled (a missed cycle),
    never a missed reading (a sparse probe column is not made up). Returns the empty bins of the stretch and
    the missed readings filled."""
    t = piece[time].to_numpy()
    before = np.concatenate([[0], np.cumsum(occupied)])
    missed = 0
    for column in piece.columns:
        if column == time:
            continue
        values = piece[column].to_numpy(dtype=float).copy()
        known = occupied & np.isfinite(values)
        if known.sum() >= 2:
            most = 0 if column in measured else GAP_PERIODS
            fill = _inner_runs(~known, lambda a, b, most=most: before[b] - before[a] <= most)
            values[fill] = np.interp(t[fill], t[known], values[known])
            if column not in measured:
                missed += int(occupied[fill].sum())
        piece[column] = values
    return int((~occupied).sum()), missed


def _inner_runs(flags: np.ndarray, keep) -> np.ndarray:
    """Indices of the flagged entries in the runs of flags that neither end of ``flags`` bounds and that
    ``keep(a, b)`` accepts (``a`` a run's first index, ``b`` one past its last)."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    inner = [(a, b) for a, b in zip(starts, ends) if a > 0 and b < len(flags) and keep(a, b)]
    return np.concatenate([np.arange(a, b) for a, b in inner]) if inner else np.zeros(0, dtype=int)


def jitter_note(label: str, time: np.ndarray, period_s: float) -> str | None:
    """A note giving the largest deviation of an interval from the period, when the clock jitters."""
    step = np.diff(time)
    deviation = np.abs(step - period_s)
    worst = int(np.argmax(deviation))
    if deviation[worst] <= 1e-6 * period_s:  # below a clock's resolution: a date written in days, a float's rounding
        return None
    return (
        f"{label}: time stamps jitter around the period of {period_s:g} s: largest deviation "
        f"{deviation[worst]:.4g} s ({100 * deviation[worst] / period_s:.2f} %, rows {worst + 1} to {worst + 2}); "
        "the samples are taken as one period apart"
    )
