"""``groupfit replay --probe-every SECONDS [--probe-column COLUMN]``: a replay with probe checks.

The checks fall every ``SECONDS`` (rounded to whole samples, and said so; the
first follows the interval's last sample, one period before ``SECONDS`` after
the first sample, or ``--probe-first`` seconds after the first sample: 0 is a
check at the first sample, a probe cycle at the start of a job), reading the
run's error column, or ``--probe-column``
(a logged check with its own error; alone, every row where that column holds
a number is a check). A check follows its sample's step, as ``gf_probe``
follows ``gf_step`` on the controller (``docs/recalibration.md``).
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from groupfit.data import length_unit, numeric_column
from groupfit.default_columns import default_temperature_columns, length_unit_named, scaled_name
from groupfit.error_scale import scaled_values
from groupfit.error_start import from_start, is_from_start, logged_spec
from groupfit.errors import InputError
from groupfit.probe_intervals import (
    check_probe_first,
    check_rows,
    nearest_sample,
    on_measured_rows,
    parse_interval,
    whole_samples,
)
from groupfit.runtime import PROBE_CODE_OFFSET, Replay
from groupfit.runtime.recalibration import PROBE_APPLIED, PROBE_IGNORED, PROBE_LIMIT_UM, PROBE_REJECTED

PROBE_NAMES = {PROBE_APPLIED: "applied", PROBE_REJECTED: "rejected", PROBE_IGNORED: "ignored"}


def add_probe_options(replay: argparse.ArgumentParser) -> None:
    """``--probe-every``, ``--probe-first`` and ``--probe-column``."""
    replay.add_argument(
        "--probe-every",
        metavar="SECONDS",
        help="replay a probe check every SECONDS (1800, or 30m, 0.5h; the error column, or --probe-column, at those "
        "samples), "
        "folded into the compensation by the model's recalibration section",
    )
    replay.add_argument(
        "--probe-first",
        type=float,
        metavar="SECONDS",
        help="with --probe-every: the first check SECONDS after the run's first sample (default: after the first "
        "interval's samples, with the sample one period before the interval's end); 0 checks at the first sample, "
        "as a probe cycle at the start of a job does",
    )
    replay.add_argument(
        "--probe-column",
        metavar="COLUMN",
        help="the probe's reading in µm, or in mm, nm by the column's name (probe_mm), or COLUMN*K (×K µm per "
        "unit as logged), COLUMN-start less the column's first reading (the run's start, as --error reads it); "
        "default: the run's error column; without --probe-every every row where it holds a number is a check",
    )


def probe_columns(spec: str | None) -> tuple[str, ...]:
    """The names ``--probe-column`` may read (as given, less ``-start``, less ``*K``): columns read on some rows
    only, which loading leaves unfilled (``sparse``)."""
    if spec is None:
        return ()
    logged = logged_spec(spec) or spec
    scaled = scaled_name(logged)
    return tuple(dict.fromkeys((spec, logged, *((scaled[0],) if scaled else ()))))


def refuse_probe_column(run, column: str, given: str) -> None:
    """Refuse the run's time, an input the model reads or a column named as a temperature sensor as the probe's
    readings: checks of seconds or °C."""
    if column == run.time_name:
        what = "the run's time"
    elif column in run.temp_names:
        what = "a reading the model takes as an input"
    elif default_temperature_columns([column]):
        what = "named as a temperature sensor"
    else:
        return
    raise InputError(
        f"{run.source}: --probe-column '{given}' is {what}, not a measured error; name the column of the probe's "
        "readings (µm), or leave the option out to check against the run's error column"
    )


def probe_schedule(args: argparse.Namespace, run, *, continued: bool = False) -> np.ndarray | None:
    """Per sample the probe reading (µm), NaN where there is no check; None without probe options.

    ``--probe-column COLUMN-start`` reads the checks less the run's first one; not on a run replayed as the rest
    of a recording (``continued``), whose first reading is not the recording's start.
    """
    args.probe_every = parse_interval(args.probe_every)
    check_probe_first(args.probe_first, args.probe_every)
    if args.probe_every is None and args.probe_column is None:
        return None
    first = args.probe_first
    if args.probe_column is not None:
        column, factor = scaled_values(run.frame, args.probe_column, run.source)
        refuse_probe_column(run, column, args.probe_column)
        reading = numeric_column(run.frame, column, run.source, allow_nonfinite=True)
        named = length_unit_named(column)
        if named is not None and column not in (args.probe_column, logged_spec(args.probe_column)):
            raise InputError(
                f"{run.source}: --probe-column '{args.probe_column}': column '{column}' is in {named} by its name and "
                f"read as µm without a factor; give --probe-column '{column}'"
            )
        reading = reading * factor * length_unit(column)[1]  # ``probe*2.5``, ``probe_mm``: read in µm
        if is_from_start(args.probe_column):
            if continued:
                raise InputError(
                    f"--probe-column '{args.probe_column}': {run.name} is replayed as the rest of a recording, and "
                    "its first reading is not the recording's start; give the checks from the recording's start "
                    f"(--probe-column '{logged_spec(args.probe_column)}')"
                )
            reading = from_start(reading)
    elif run.error is not None:
        reading = np.asarray(run.error, dtype=float)
    else:
        raise InputError(f"{run.source}: no error column for the probe checks; name one with --probe-column")
    probes = np.full(run.n_samples, np.nan)
    if args.probe_every is None:
        rows = np.arange(run.n_samples)
    else:
        every = whole_samples(args.probe_every, run.period)
        rows = check_rows(run.n_samples, every, None if first is None else nearest_sample(first, run.period))
        if not rows.size:
            last = (run.n_samples - 1) * run.period
            raise InputError(
                f"--probe-first {first:g}: after the run's last sample ({last:g} s); give an earlier first check"
                if first is not None
                else f"--probe-every {args.probe_every:g}: the run ends at {last:g} s, before its first check; "
                "give a shorter interval or --probe-first SECONDS"
            )
        rows = on_measured_rows(rows, np.isfinite(reading))
    probes[rows] = reading[rows]
    probes[~np.isfinite(probes)] = np.nan  # an infinite reading is no reading: no check there
    return probes


def probe_summary(
    args: argparse.Namespace, replay: Replay, probes: np.ndarray, rms_without: float | None, period: float
) -> dict:
    """The ``probes`` object of ``replay --json``: the schedule (``every_s`` the interval the checks fell at,
    whole samples; ``asked_every_s`` the one asked for), the counts and every check's outcome."""
    counts = replay.probe_counts()
    checks = []
    for i in np.flatnonzero(replay.probe):
        code = int(replay.probe[i]) - PROBE_CODE_OFFSET
        checks.append({"i": int(i) + 1, "reading_um": float(probes[i]), "result": PROBE_NAMES[code]})
    return {
        "every_s": None if args.probe_every is None else whole_samples(args.probe_every, period) * period,
        "asked_every_s": args.probe_every,
        "first_s": args.probe_first,
        "first_check_s": None if args.probe_first is None else nearest_sample(args.probe_first, period) * period,
        "column": args.probe_column,
        **counts,
        "rms_without_checks_um": rms_without,
        "checks": checks,
    }


def sample_probe(replay: Replay, k: int) -> str | None:
    """What the check at sample ``k`` (0-based) came to, or None without one."""
    if replay.probe is None or not replay.probe[k]:
        return None
    return PROBE_NAMES[int(replay.probe[k]) - PROBE_CODE_OFFSET]


def probe_report(result: dict[str, Any]) -> str:
    """The summary line of the checks."""
    p = result["probes"]
    schedule = f"every {p['every_s']:g} s" if p["every_s"] is not None else f"logged in '{p['column']}'"
    if p["every_s"] is not None and not math.isclose(p["every_s"], p["asked_every_s"], rel_tol=1e-9):
        schedule += f" ({p['asked_every_s']:g} s asked, rounded to whole samples)"
    if p["first_s"] is not None:
        schedule += f", the first at {p['first_check_s']:g} s"
        if not math.isclose(p["first_check_s"], p["first_s"], rel_tol=1e-9, abs_tol=1e-9):
            schedule += f" ({p['first_s']:g} s asked, rounded to whole samples)"
    why = "sensor fault or no reading"
    beyond = sum(abs(c["reading_um"]) > PROBE_LIMIT_UM for c in p["checks"])
    if beyond:
        why += (
            f"; {beyond} of them read beyond ±{PROBE_LIMIT_UM:g} µm, which no routine takes for a reading: a "
            "probe column in another unit? --probe-column 'COLUMN*K' reads it ×K µm"
        )
    line = (
        f"probes   {len(p['checks'])} check(s) {schedule}: {p['applied']} applied, {p['rejected']} rejected "
        f"by the gate (flagged, not applied), {p['ignored']} ignored ({why})"
    )
    if p["rms_without_checks_um"] is not None and result["rms_um"] is not None:
        line += f"; RMS {result['rms_um']:.4g} µm with them, {p['rms_without_checks_um']:.4g} µm without"
    return line


__all__ = ["probe_report", "probe_schedule", "probe_summary", "sample_probe"]
