"""Glitches in a measured error: single readings that leave their neighbours and come back.

A thermal error moves slowly: from one sample to the next it changes by a
small share of its range, and even a step (a spindle started) stays where it
went. A reading that jumps far from both sides and returns within a few
samples is the measurement's fault (a laser beam interrupted, a probe that
lifted, a logger that wrote 0), and one of them can pull a least-squares fit
and every figure built on it (a single +300 µm reading lifts the RMS of a
1.4 µm model to 6 µm).

A reading is a glitch when it stands out from the running median of its
:data:`WINDOW` neighbours (itself included) by more than both
:data:`SIGMAS` robust standard deviations of all such departures and
:data:`RANGE_SHARE` of the error's range (the 1st to 99th percentile of the
running median): so up to ``WINDOW // 2`` glitches in a row are found, a
step of the error is not one (the median follows it within half a window)
and neither is the noise of a quiet run. The first and last ``WINDOW // 2``
readings, whose neighbours lie on one side only, are glitches when they lie
beyond the span of the :data:`WINDOW` readings after (before) them by the same
threshold: a sensor's power-on reading (a DS18B20's 85 °C) comes first. Only
finite readings count; a log whose error is measured on fewer than
:data:`MIN_MEASURED_SHARE` of its rows (a probe cycle every few minutes) is
not tested: its readings lie too far apart to tell a glitch from a change
(one in 20 rows of a speed-step run already showed one).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from groupfit.default_columns import ambient_columns

WINDOW = 7
"""Readings in the running median (centred)."""
SIGMAS = 10.0
"""Robust standard deviations (1.4826 × MAD) of the departures from the running median a glitch exceeds."""
RANGE_SHARE = 0.5
"""Share of the error's range (the running median's 1st to 99th percentile) a glitch departs by at least: a real
error sampled sparsely can show a narrow dip of a quarter of its range; no real error swings by half of it and
back within a few samples."""
MIN_MEASURED_SHARE = 0.5
"""Share of a run's rows the error must be measured on for glitches to be looked for."""
SHOWN = 5
"""Glitches named in the note; the rest are counted."""


TEMPERATURE_RANGE_SHARE = 2.0
"""Share of a sensor's range a temperature glitch departs by at least (a DS18B20's 85 °C power-on reading
on a frame at 22 °C): a short bump of a real sensor (a coolant jet, a door opened) stays within its range."""


def error_glitches(error: np.ndarray, *, range_share: float = RANGE_SHARE) -> np.ndarray:
    """Indices (0-based, sorted) of the glitches in ``error`` (NaN: not measured, never a glitch); a glitch
    departs by ``range_share`` of the range at least."""
    error = np.asarray(error, dtype=float)
    rows = np.flatnonzero(np.isfinite(error))
    half = WINDOW // 2
    if len(rows) < max(2 * WINDOW, MIN_MEASURED_SHARE * len(error)):
        return np.array([], dtype=int)
    values = error[rows]
    median = pd.Series(values).rolling(WINDOW, center=True, min_periods=1).median().to_numpy()
    departure = values - median
    spread = 1.4826 * float(np.median(np.abs(departure - np.median(departure))))
    low, high = np.percentile(median, [1, 99])  # the running median's: glitches do not widen it
    threshold = max(SIGMAS * spread, range_share * float(high - low))
    if not threshold > 0:
        return np.array([], dtype=int)
    n = len(values)
    for i in [*range(half), *range(n - half, n)]:
        beyond = values[i + 1 : i + 1 + WINDOW] if i < half else values[max(0, i - WINDOW) : i]
        departure[i] = values[i] - float(np.clip(values[i], beyond.min(), beyond.max()))
    flagged = np.abs(departure) > threshold
    return rows[flagged]


def glitch_note(column: str, label: str, error: np.ndarray, glitches: np.ndarray) -> str:
    """One line naming the glitches (1-based data rows, as the loader's messages count them) and what was done."""
    shown = ", ".join(f"row {i + 1}: {error[i]:.4g} µm" for i in glitches[:SHOWN])
    more = f" and {len(glitches) - SHOWN} more" if len(glitches) > SHOWN else ""
    return (
        f"{label}: {len(glitches)} reading(s) of '{column}' leave their neighbours and come back ({shown}{more}), "
        "a measuring glitch: left out as not measured; --keep-glitches keeps them"
    )


def without_glitches(error: np.ndarray, column: str, label: str) -> tuple[np.ndarray, np.ndarray, str | None]:
    """``error`` with its glitches as NaN (not measured), their indices, and the note naming them (None: none)."""
    error = np.asarray(error, dtype=float)
    glitches = error_glitches(error)
    if not glitches.size:
        return error, glitches, None
    note = glitch_note(column, label, error, glitches)
    error = error.copy()
    error[glitches] = np.nan
    return error, glitches, note


def temperatures_without_glitches(
    frame: pd.DataFrame,
    temps: list[str],
    readings: np.ndarray,
    label: str,
    ambient: str | None = None,
    plausible: tuple[float, float] | None = None,
    *,
    as_logged: bool = False,
) -> tuple[pd.DataFrame, np.ndarray, str | None]:
    """The inputs' ``readings`` and the frame's columns of the air's temperature (the references the inputs
    may be taken against: ``ambient``, the column ``--ambient`` names, and those named as the air's,
    :func:`~groupfit.default_columns.ambient_columns`) with each sensor's glitches (departing by
    :data:`TEMPERATURE_RANGE_SHARE` of its range) interpolated from its neighbours, and a note naming them
    (None: none; the frame and readings are then those given). A reading outside the ``plausible`` range
    (°C) is no glitch, nor a neighbour to interpolate from: it is refused, or kept as a fault of the run-time
    rule (a validation run), as one that is not a number is.

    ``as_logged``: a validation run, scored as ``replay`` scores a next run: the glitches are named in the
    note but every reading is kept as logged (the frame and readings those given), for the run-time rule
    to read as the controller reads it."""
    given = readings
    readings = np.array(readings, dtype=float)
    found = []
    for j, name in enumerate(temps):
        readings[:, j], shown = _interpolated_glitches(readings[:, j], name, plausible)
        found += shown
    cleaned = {}
    named = [ambient] if ambient in frame.columns and ambient not in temps else []
    for name in dict.fromkeys([*named, *ambient_columns(frame, temps)]):
        values = pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
        cleaned[name], shown = _interpolated_glitches(values, name, plausible)
        found += shown
    if not found:
        return frame, readings, None
    more = f" and {len(found) - SHOWN} more" if len(found) > SHOWN else ""
    named = (
        f"{label}: {len(found)} temperature reading(s) leave their neighbours and come back "
        f"({', '.join(found[:SHOWN])}{more}), a sensor's glitch: "
    )
    if as_logged:
        return frame, given, named + "kept as logged in a validation run, scored as replay scores it"
    frame = frame.assign(**{name: values for name, values in cleaned.items()}) if cleaned else frame
    return frame, readings, named + "interpolated from its neighbours; --keep-glitches keeps them"


def _interpolated_glitches(
    values: np.ndarray, name: str, plausible: tuple[float, float] | None = None
) -> tuple[np.ndarray, list[str]]:
    """One sensor's readings with its glitches interpolated from its neighbours, and the glitches named; a
    reading outside ``plausible`` is passed over as one that is not a number is."""
    read = values
    if plausible is not None:
        with np.errstate(invalid="ignore"):
            read = np.where((values >= plausible[0]) & (values <= plausible[1]), values, np.nan)
    glitches = error_glitches(read, range_share=TEMPERATURE_RANGE_SHARE)
    if not glitches.size:
        return values, []
    shown = [f"'{name}' row {i + 1}: {values[i]:.4g} °C" for i in glitches]
    kept = np.setdiff1d(np.flatnonzero(np.isfinite(read)), glitches)
    values = values.copy()
    values[glitches] = np.interp(glitches, kept, values[kept])
    return values, shown


def scored_glitches(error: np.ndarray | None, residual: np.ndarray | None) -> tuple[dict, list[str]]:
    """A replay's glitches: ``{"glitch_rows": [...], "rms_without_glitches_um": x}`` and a note, or nothing.

    ``replay`` scores every reading as logged (a next run's RMS is what the
    log says); the note gives the RMS without the glitches beside it.
    """
    if error is None or residual is None:
        return {}, []
    glitches = error_glitches(error)
    glitches = glitches[np.isfinite(residual[glitches])]  # on a sample the replay scored (not in sensor fault)
    if not glitches.size:
        return {}, []
    kept = np.ones(len(residual), dtype=bool)
    kept[glitches] = False
    scored = residual[kept & np.isfinite(residual)]
    rms = float(np.sqrt(np.mean(scored**2))) if scored.size else float("nan")
    rows = ", ".join(str(i + 1) for i in glitches[:SHOWN]) + (" …" if len(glitches) > SHOWN else "")
    note = (
        f"{len(glitches)} reading(s) of the error leave their neighbours and come back (rows {rows}), a measuring "
        f"glitch: the RMS counts them; without them it is {rms:.4g} µm"
    )
    return {"glitch_rows": [int(i) + 1 for i in glitches], "rms_without_glitches_um": rms}, [note]


__all__ = [
    "MIN_MEASURED_SHARE",
    "RANGE_SHARE",
    "SIGMAS",
    "TEMPERATURE_RANGE_SHARE",
    "WINDOW",
    "error_glitches",
    "glitch_note",
    "scored_glitches",
    "temperatures_without_glitches",
    "without_glitches",
]
