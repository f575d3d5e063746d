"""Error against the probe-check interval: ``groupfit compare --probe-every 5m,15m,30m,60m,120m``.

Every compared model's residual on every validation run is replayed with a
check every T through the offset hold (each check's residual held until the
next; :mod:`groupfit.runtime.recalibration` with ``method = "hold"`` and no
bound acting), so a user reads off the longest interval that meets a
tolerance (``--tolerance UM`` prints it per model). The hold is the one filter every model can take without tuning;
a model file tuned with ``fit --recalibrate`` usually does better
(``groupfit replay --probe-every``).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from groupfit.data_options import positive_number
from groupfit.errors import InputError
from groupfit.io import save_figure

UNITS_S = {"": 1.0, "s": 1.0, "m": 60.0, "min": 60.0, "h": 3600.0}
MAX_CHECK_S = 1.0e9
RUN_MARKERS = ("o", "s", "^", "D", "v", "P", "X")
RUN_LINES = ("-", "--", "-.")
"""A run's marker and line style in the interval plot (its colour is the model's)."""
"""The longest check interval or first check (s, some 30 years): beyond it a number is a slip, not a schedule."""


def parse_intervals(text: str) -> list[float]:
    """``"5m,15m,1h,900"`` as seconds (a bare number: seconds); InputError naming the bad entry."""
    intervals = []
    for item in text.split(","):
        match = re.fullmatch(r"\s*([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(s|min|m|h)?\s*", item)
        if not match:
            raise InputError(f"--probe-every: {item.strip()!r} is not an interval; write e.g. 5m,15m,30m,1h or 900")
        seconds = float(match.group(1)) * UNITS_S[match.group(2) or ""]
        if not (math.isfinite(seconds) and seconds > 0):
            raise InputError(f"--probe-every: {item.strip()!r} must be longer than 0")
        if seconds > MAX_CHECK_S:
            raise InputError(
                f"--probe-every: {item.strip()!r} is longer than {MAX_CHECK_S:g} s: write the interval in s, m or h "
                "(e.g. 30m)"
            )
        if seconds in intervals:
            raise InputError(f"--probe-every: {item.strip()!r} repeats an interval given before ({seconds:g} s)")
        intervals.append(seconds)
    return intervals


def parse_interval(text: str | float | None) -> float | None:
    """One ``--probe-every`` interval (``1800``, ``30m``, ``0.5h``) in seconds; None stays None."""
    if text is None or isinstance(text, (int, float)):
        return text
    if "," in text:
        raise InputError(f"--probe-every {text}: replay takes one interval (compare --probe-every takes several)")
    return parse_intervals(text)[0]


def check_intervals_fit(intervals_s: Sequence[float], first_s: float | None, runs: Sequence) -> None:
    """Refuse an interval after which no check falls in some run (the checked RMS would be the unchecked one,
    reported as a result), and a first check after a run's end. An interval shorter than a sample is taken, as
    ``replay`` takes it: a check on every sample (:func:`whole_samples`, said by :func:`rounded_interval_notes`)."""
    for run in runs:
        length_s = (run.n_samples - 1) * run.period
        if first_s is not None and first_s > length_s:
            raise InputError(f"--probe-first {first_s:g}: after the end of {run.source} ({length_s:g} s)")
        for interval in intervals_s:
            if first_s is None and interval > length_s:
                raise InputError(
                    f"--probe-every: {_label(interval)} is longer than {run.source} ({length_s:g} s): no check "
                    "would fall in it; give shorter intervals or --probe-first 0"
                )


def whole_samples(seconds: float, period: float) -> int:
    """The samples of an interval of checks: ``seconds`` rounded to whole sampling periods, at least one."""
    return max(1, nearest_sample(seconds, period))


def nearest_sample(seconds: float, period: float) -> int:
    """``seconds`` as whole sampling periods, a half rounded up (a check is never placed before the time asked
    for by Python's rounding of halves to even: 250 s at 100 s is 3 periods, not 2)."""
    return int(math.floor(seconds / period + 0.5))


def rounded_interval_notes(intervals_s: Sequence[float], runs: Sequence, first_s: float | None = None) -> list[str]:
    """A note per run and interval (and ``--probe-first``) that is not a whole number of the run's samples: its
    checks fall at the nearest whole number of samples (a half rounded up)."""
    notes = []
    for run in runs:
        used_first = None if first_s is None else nearest_sample(first_s, run.period) * run.period
        if used_first is not None and intervals_s and not math.isclose(used_first, first_s, rel_tol=1e-9):
            notes.append(
                f"--probe-first {first_s:g}: {run.source} is sampled every {run.period:g} s, so its first check "
                f"falls {used_first:g} s after its start (whole samples)"
            )
        for interval in intervals_s:
            used = whole_samples(interval, run.period) * run.period
            if not math.isclose(used, interval, rel_tol=1e-9):
                notes.append(
                    f"--probe-every {_label(interval)}: {run.source} is sampled every {run.period:g} s, so its "
                    f"checks fall every {used:g} s (whole samples)"
                )
    return notes


def check_probe_first(first_s: float | None, intervals) -> None:
    """``--probe-first SECONDS``: with ``--probe-every``, a number of seconds >= 0 (InputError otherwise)."""
    if first_s is None:
        return
    if not intervals:
        raise InputError("--probe-first needs --probe-every: give the interval of the checks too")
    if not (math.isfinite(first_s) and 0 <= first_s <= MAX_CHECK_S):
        raise InputError(f"--probe-first {first_s:g}: must be a number of seconds from 0 to {MAX_CHECK_S:g}")


def check_rows(n_samples: int, every: int, first: int | None = None) -> np.ndarray:
    """The 0-based samples a check follows: every ``every`` samples from ``first`` (default ``every − 1``,
    one interval in; ``--probe-first``), as ``replay --probe-every`` and ``compare --probe-every`` place them."""
    return np.arange(every - 1 if first is None else first, n_samples, every)


def on_measured_rows(rows: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Each check moved to the first row at or after it that has a reading, if one comes before the next check.

    A log whose error is measured on some rows only (a probe cycle every few
    minutes) is checked when it was measured; a row due without a reading up
    to the next check has no check.
    """
    n = len(measured)
    following = np.minimum.accumulate(np.where(measured, np.arange(n), n)[::-1])[::-1]
    moved = following[rows]
    return moved[moved < np.r_[rows[1:], n]]


def hold_residual(residual: np.ndarray, every: int, first: int | None = None) -> np.ndarray:
    """The residual after a check at :func:`check_rows` (on the next measured row: :func:`on_measured_rows`),
    each held from the next sample until the next check."""
    residual = np.asarray(residual, dtype=float)
    rows = on_measured_rows(check_rows(len(residual), every, first), np.isfinite(residual))
    if not rows.size:
        return residual.copy()
    last = np.searchsorted(rows, np.arange(len(residual)), side="left") - 1  # the last check strictly before
    return residual - np.where(last >= 0, residual[rows[np.maximum(last, 0)]], 0.0)


def interval_table(
    errors: Mapping[str, np.ndarray],
    predictions: Mapping[str, Mapping[str, np.ndarray]],
    periods: Mapping[str, float],
    intervals_s: Sequence[float],
    first_s: float | None = None,
) -> dict[str, Any]:
    """Per model and run the RMS without checks and with a check every interval (the ``--json`` object).

    ``first_s``: the first check that many seconds after a run's first sample (default: one interval in).
    """
    rows = []
    for run, error in errors.items():
        first = None if first_s is None else nearest_sample(first_s, periods[run])
        for model, prediction in predictions[run].items():
            residual = np.asarray(error, dtype=float) - np.asarray(prediction, dtype=float)
            rms = [_rms(hold_residual(residual, whole_samples(t, periods[run]), first)) for t in intervals_s]
            rows.append({"model": model, "run": run, "rms_none_um": _rms(residual), "rms_um": rms})
    return {"method": "offset hold", "intervals_s": [float(t) for t in intervals_s], "first_s": first_s, "rows": rows}


def interval_plan(table: Mapping[str, Any], tolerance_um: float) -> dict[str, Any]:
    """Per model the longest interval of ``table`` whose RMS with checks is at most ``tolerance_um`` on every
    run (the ``--json`` object ``plan``).

    Per model: ``longest_interval_s`` (None when no interval meets it) and
    ``without_checks`` (the RMS without checks meets it on every run already).
    """
    intervals = table["intervals_s"]
    models: dict[str, dict[str, Any]] = {}
    for row in table["rows"]:
        entry = models.setdefault(row["model"], {"meets": [True] * len(intervals), "without_checks": True})
        entry["meets"] = [m and v <= tolerance_um for m, v in zip(entry["meets"], row["rms_um"])]
        entry["without_checks"] = entry["without_checks"] and row["rms_none_um"] <= tolerance_um
    plan = {}
    for model, entry in models.items():
        meeting = [t for t, ok in zip(intervals, entry["meets"]) if ok]
        plan[model] = {
            "longest_interval_s": max(meeting) if meeting else None,
            "without_checks": entry["without_checks"],
        }
    return {"tolerance_um": float(tolerance_um), "models": plan}


def plan_summary(plan: Mapping[str, Any]) -> str:
    """The lines ``compare --probe-every … --tolerance UM`` prints: per model the longest interval that meets it."""
    tolerance = plan["tolerance_um"]
    lines = [f"plan    the longest check interval with RMS ≤ {tolerance:g} µm on every run (offset hold):"]
    for model, entry in plan["models"].items():
        if entry["without_checks"]:
            said = "no checks needed (RMS without checks meets it)"
        elif entry["longest_interval_s"] is None:
            said = "none of the intervals tried: check more often or improve the model"
        else:
            said = f"a check every {_label(entry['longest_interval_s'])}"
        lines.append(f"        {model:<12} {said}")
    return "\n".join(lines)


def parse_tolerance(text: str | None, intervals) -> float | None:
    """``--tolerance UM``: with ``--probe-every``, a finite number of µm > 0 (InputError otherwise); None when
    not given."""
    if text is None:
        return None
    if not intervals:
        raise InputError("--tolerance needs --probe-every: give the check intervals to try, e.g. 15m,30m,60m,120m")
    return positive_number(text, "--tolerance", "the largest acceptable RMS error in µm, e.g. 2")


def _rms(values: np.ndarray) -> float:
    values = values[np.isfinite(values)]
    return float(np.sqrt(np.mean(values**2))) if values.size else math.nan


def _label(seconds: float) -> str:
    if seconds >= 3600 and seconds % 3600 == 0:
        return f"{seconds / 3600:g} h"
    return f"{seconds / 60:g} min" if seconds % 60 == 0 else f"{seconds:g} s"


def interval_summary(table: Mapping[str, Any]) -> str:
    """The table ``compare --probe-every`` prints: RMS (µm) against the check interval, per model and run."""
    heads = ["none"] + [_label(t) for t in table["intervals_s"]]
    lines = [
        f"RMS µm with a probe check every T ({table['method']}"
        + ("" if table.get("first_s") is None else f", the first {table['first_s']:g} s after the run's start")
        + "), per model and validation run",
        f"{'model':<12} {'run':<20}" + "".join(f"{h:>9}" for h in heads),
    ]
    for row in table["rows"]:
        values = [row["rms_none_um"], *row["rms_um"]]
        lines.append(f"{row['model']:<12} {row['run']:<20}" + "".join(f"{v:>9.3g}" for v in values))
    return "\n".join(lines)


def plot_intervals(table: Mapping[str, Any], path: Path, tolerance_um: float | None = None) -> None:
    """RMS against the check interval, one line per model and run: a colour per model, a marker and line style
    per run; the RMS without checks at the right, "none", joined dotted and with the run's marker hollow
    (dashed: the tolerance, when given)."""
    fig = Figure(figsize=(8, 5), layout="constrained")
    ax = fig.subplots()
    minutes = np.asarray(table["intervals_s"]) / 60.0
    unchecked = minutes.max() * (2.0 if minutes.size < 2 else max(2.0, minutes.max() / minutes.min()) ** 0.25)
    models = list(dict.fromkeys(row["model"] for row in table["rows"]))
    runs = list(dict.fromkeys(row["run"] for row in table["rows"]))
    palette = colormaps["tab10" if len(models) <= 10 else "tab20"]
    for row in table["rows"]:
        color = palette(models.index(row["model"]) % palette.N)
        k = runs.index(row["run"])
        style = dict(marker=RUN_MARKERS[k % len(RUN_MARKERS)], ls=RUN_LINES[k // len(RUN_MARKERS) % len(RUN_LINES)])
        ax.plot(minutes, row["rms_um"], color=color, lw=1.2, label=f"{row['model']} on {row['run']}", **style)
        last = int(np.argmax(minutes))
        ax.plot([minutes[last], unchecked], [row["rms_um"][last], row["rms_none_um"]], color=color, lw=0.8, ls=":")
        ax.plot(unchecked, row["rms_none_um"], color=color, marker=style["marker"], mfc="none", ls="none")
    if tolerance_um is not None:
        ax.axhline(tolerance_um, color="k", lw=1.0, ls="--", label=f"tolerance {tolerance_um:g} µm")
    ax.set_xscale("log")
    ax.set_xticks([*minutes, unchecked], [*(_label(t) for t in table["intervals_s"]), "none"])
    ax.minorticks_off()
    ax.set_xlabel("probe check every")
    ax.set_ylabel("RMS error with checks (µm)")
    ax.set_title(f"error against the check interval ({table['method']})")
    ax.legend(fontsize=7, loc="best")
    save_figure(fig, path, dpi=120)


__all__ = [
    "rounded_interval_notes",
    "whole_samples",
    "check_probe_first",
    "check_rows",
    "hold_residual",
    "interval_plan",
    "interval_summary",
    "interval_table",
    "parse_intervals",
    "parse_tolerance",
    "plan_summary",
    "plot_intervals",
]
