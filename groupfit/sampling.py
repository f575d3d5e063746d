"""A run's clock: uniformly sampled, or stamps cut coarser than the period spread as the clock that wrote them."""

from __future__ import annotations

import numpy as np

from groupfit.cut_stamps import spread_within_stamps
from groupfit.data_options import MAX_PERIOD_TOLERANCE
from groupfit.errors import InputError
from groupfit.resample import GAP_PERIODS
from groupfit.timestamps import clock_restart, hour_off, refuse_clock_change, restart_refusal, stamp_resolution

MIN_PERIOD_S = 1e-4
"""The shortest sampling period a run may have (s): a thermal log is never sampled at more than 10 kHz, and a
clock read in another unit than seconds (ns counted as s) would be."""


def clock_of(time: np.ndarray, label: str, column: str, *, tolerance: float) -> tuple[np.ndarray, float, str | None]:
    """The run's times, its period and a note: as stamped when they pass :func:`check_time`, else spread within
    stamps cut coarser than the period (:func:`~groupfit.cut_stamps.spread_within_stamps`) when one uniform
    clock places every row inside its own; refused as :func:`check_time` refuses them otherwise."""
    try:
        return time, check_time(time, label, column, tolerance=tolerance), None
    except InputError:
        spread, note = spread_within_stamps(time, label, column)
        if note is None:
            raise
    return spread, check_time(spread, label, column, tolerance=tolerance), note


def check_time(time: np.ndarray, label: str, column: str, *, tolerance: float) -> float:
    """Check that ``time`` is strictly increasing and uniformly sampled within ``tolerance`` (or within the
    stamps' resolution, :func:`~groupfit.timestamps.stamp_resolution`, their mean step then the period);
    return the period."""
    if len(time) < 2:
        raise InputError(f"{label}: only {len(time)} sample(s); a run needs at least two")
    step = np.diff(time)
    refuse_clock_change(time, label, column)
    if np.any(step <= 0):
        i = int(np.argmax(step <= 0)) + 1
        if clock_restart(time) == i:  # a restarted clock goes on from its new start; a bad cell is alone
            raise restart_refusal(time, i, label, column)
        raise InputError(
            f"{label}: column '{column}' is not strictly increasing at row {i + 1} "
            f"({time[i]:g} s after {time[i - 1]:g} s); sort the rows, remove the duplicate, or average the "
            "readings of each period with --resample SECONDS"
        )
    period = float(np.median(step))
    if period < MIN_PERIOD_S:
        raise InputError(
            f"{label}: column '{column}' steps {period:g} s from row to row, faster than any thermal log (at least "
            f"{MIN_PERIOD_S:g} s); give the time in seconds, or name its unit in the column (time_ms, time [ms])"
        )
    deviation = np.abs(step - period)
    irregular = deviation > max(tolerance * period, stamp_resolution(time, period) * (1 + 1e-9))
    if np.any(irregular):
        i = int(np.argmax(irregular)) + 1
        widen = (
            "widen the tolerance with --period-tolerance PERCENT, "
            if abs(step[i - 1] - period) < MAX_PERIOD_TOLERANCE * period
            else ""
        )
        hour = (
            "; an hour more than the period: if daylight saving time began there, write the time stamps with "
            "their UTC offset (2026-03-29T03:00:00+02:00) or in UTC. Otherwise"
            if hour_off(step[i - 1], period, 1)
            else ";"
        )
        raise InputError(
            f"{label}: sampling is not uniform: rows {i} to {i + 1} of column '{column}' are "
            f"{step[i - 1]:g} s apart but the period is {period:g} s (tolerance {100 * tolerance:g} %){hour} "
            f"average the readings of each period with --resample SECONDS (up to {GAP_PERIODS} missed periods in a "
            f"row are interpolated, a longer gap splits the run), {widen}or split the run at the gap"
        )
    if np.any(deviation > tolerance * period):  # stamps rounded to their resolution: the period is their mean
        period = float(time[-1] - time[0]) / (len(time) - 1)
    return period


PAUSE_RATIO = 2.0
"""A pause between bursts is at least this many times as long as any step within a burst."""


def burst_cycle(time: np.ndarray) -> tuple[int, float] | None:
    """The readings per burst (the most common count) and the mean period of a log whose readings come in
    bursts (a 3-D printer that probes three times 4 s apart about once a minute); None when the log is not one.

    The steps of such a log fall in two kinds: those within a burst (0 where the readings of a burst share a
    stamp written to the second), and pauses at least :data:`PAUSE_RATIO` times as long as any of those, or as
    the stamps' resolution. The log is one when it holds at least four bursts, most of two readings or
    more, and periods of the mean length, laid from the first burst on (a burst missed leaves one period empty),
    hold each burst whole: its start strays from that clock, plus its length, by less than half a period.
    """
    step = np.diff(time)
    if time.size < 6 or np.any(step < 0):
        return None
    ordered = np.sort(step)
    floor = max(stamp_resolution(time), np.finfo(float).tiny)  # readings of a burst may share a coarse stamp
    jumps = ordered[1:] / np.maximum(ordered[:-1], floor)
    split = int(np.argmax(jumps))
    if jumps[split] < PAUSE_RATIO:
        return None
    starts = np.concatenate([[0], np.flatnonzero(step > ordered[split]) + 1])
    ends = np.append(starts[1:], time.size) - 1
    readings = int(np.bincount(ends - starts + 1).argmax())
    if readings < 2 or starts.size < 4:
        return None
    between = np.diff(time[starts])
    cycles = np.round(between / np.median(between))
    if np.any(cycles < 1):
        return None
    period = float(time[starts[-1]] - time[0]) / cycles.sum()
    stray = time[starts] - time[0] - period * np.concatenate([[0.0], np.cumsum(cycles)])
    if np.ptp(stray) + np.max(time[ends] - time[starts]) < period / 2:
        return readings, period
    return None


def described_burst_cycle(time: np.ndarray) -> tuple[str, float] | None:
    """What a note says of a log read in bursts and its period (:func:`burst_cycle`); None when it is not one."""
    cycle = burst_cycle(time)
    if cycle is None:
        return None
    return (
        f"the readings come in bursts of {cycle[0]} every {cycle[1]:g} s: each burst averaged into one sample",
        cycle[1],
    )


__all__ = ["burst_cycle", "check_time", "clock_of", "described_burst_cycle"]
