"""Read a ball-screw run: sensor positions from the column names, rises above ambient.

A screw run is an ordinary groupfit run (``time_s``, temperatures in °C,
``error_um``) whose temperature columns carry their distance from the heat
source in millimetres, ``T<mm>mm`` (``T0mm``, ``T20mm`` … ``T140mm``), and
whose ``probe_x_m`` column gives the position (m) of the displacement probe
(the interferometer) at each sample. The ambient temperature is the
``T_amb`` column when there is one, else the mean of the sensors at the first
sample (a run starts at ambient, as in the paper).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from groupfit.data import (
    DEFAULT_ERROR,
    DEFAULT_TIME,
    ERROR_LIMIT_UM,
    PERIOD_TOLERANCE,
    TEMP_RANGE_C,
    Run,
    load_run,
    numeric_column,
    read_table,
    without_implausible_errors,
)
from groupfit.errors import InputError

SENSOR_NAME = re.compile(r"^T(\d+(?:\.\d+)?)mm$")
LOOSE_SENSOR_NAME = re.compile(r"^T\s*_?\d+(?:[.,]\d+)?\s*_?(?:mm|cm|m)(?![a-z])", re.IGNORECASE)
"""A name that reads as a sensor's position without being ``T<mm>mm`` (``T140 mm``, ``T0mm_x``): noted, not read."""
PROBE_COLUMN = "probe_x_m"


@dataclass(frozen=True)
class ScrewRun:
    """One screw run, sensors sorted by their distance from the source.

    Attributes
    ----------
    name : str
    source : str
        Where the run came from (for messages).
    time : ndarray, shape (N,)
    names : tuple of str
        Sensor columns.
    positions : ndarray, shape (k,)
        Sensor distances from the heat source (m).
    rises : ndarray, shape (N, k)
        Temperature rises above ambient (K).
    ambient : float
        Ambient temperature (°C).
    error : ndarray, shape (N,) or None
        Measured thermal error at the probe (µm).
    probe_x : ndarray, shape (N,) or None
        Probe position (m) at each sample.
    run : Run
    """

    name: str
    source: str
    time: np.ndarray
    names: tuple[str, ...]
    positions: np.ndarray
    rises: np.ndarray
    ambient: float
    error: np.ndarray | None
    probe_x: np.ndarray | None
    run: Run

    @property
    def duration(self) -> float:
        return float(self.time[-1] - self.time[0])


def sensor_positions(columns) -> dict[str, float]:
    """``{column: x_m}`` for every column named ``T<mm>mm``."""
    return {c: float(m.group(1)) / 1000.0 for c in columns if (m := SENSOR_NAME.match(str(c)))}


def load_screw_run(
    source,
    *,
    probe_x: float | None = None,
    require_error: bool = False,
    name=None,
    period_tolerance: float = PERIOD_TOLERANCE,
    resample: float | None = None,
    encoding: str | None = None,
    temp_range: tuple[float, float] = TEMP_RANGE_C,
    error_limit: float = ERROR_LIMIT_UM,
    scored_only: bool = False,
    time: str | None = None,
    error: str | None = None,
) -> ScrewRun:
    """Load and check a screw run.

    Parameters
    ----------
    source : path or DataFrame
    probe_x : float, optional
        Probe position (m) when the run has no ``probe_x_m`` column.
    require_error : bool
        Refuse a run without ``error_um``.
    period_tolerance, resample
        How the run's clock is read, as by :func:`groupfit.data.load_run`
        (a resampled run's ambient and probe position are its periods' means).
    temp_range, error_limit
        The plausible readings (°C; |µm|): one outside is refused.
    scored_only : bool
        Take an error beyond ``error_limit`` as not measured (a replay's score), with a note, instead.
    time, error : str, optional
        The time (s) and thermal-error columns asked for (``--time``, ``--error COLUMN`` or ``COLUMN*K``; an
        error in µm, or mm, nm by its name); by default ``time_s`` and ``error_um``. An error column asked for
        and not in the run is refused.

    Raises
    ------
    InputError
        No ``T<mm>mm`` columns, two sensors at one position, a bad value.
    """
    frame, run_name, label = read_table(source, name, encoding)
    positions = sensor_positions(frame.columns)
    if not positions:
        raise InputError(
            f"{label}: no sensor columns named T<mm>mm (e.g. T0mm, T20mm: the distance from the heat source in mm)"
        )
    order = sorted(positions, key=positions.get)
    xs = np.array([positions[c] for c in order])
    if np.any(np.diff(xs) == 0):
        dup = order[int(np.flatnonzero(np.diff(xs) == 0)[0]) + 1]
        raise InputError(f"{label}: column '{dup}' is at the same position as another sensor")
    run = load_run(
        frame,
        temps=order,
        time=time or DEFAULT_TIME,
        error=error or DEFAULT_ERROR,
        require_error=require_error,
        name=run_name,
        period_tolerance=period_tolerance,
        resample=resample,
        temp_range=temp_range,
        error_limit=None if scored_only else error_limit,
    )
    if error is not None and run.error is None:
        raise InputError(
            f"{label}: --error '{error}': no such column; name the thermal-error column. The columns are: "
            + ", ".join(map(str, frame.columns))
        )
    if scored_only:
        run = without_implausible_errors(run, error_limit)
    stray = [str(c) for c in frame.columns if c not in positions and LOOSE_SENSOR_NAME.match(str(c))]
    notes = run.notes
    if stray:
        listed = ", ".join(f"'{c}'" for c in stray)
        notes = (*notes, f"{label}: {listed} read as no sensor: a sensor's column is named T<mm>mm (e.g. T140mm)")
    run = Run(**{**run.__dict__, "source": label, "notes": notes})
    frame = run.frame
    ambient = float(frame["T_amb"].iloc[0]) if "T_amb" in frame.columns else float(np.mean(run.temps[0]))
    if PROBE_COLUMN in frame.columns and probe_x is not None:
        raise InputError(
            f"{label}: --probe-x {probe_x:g} given, but the run's column {PROBE_COLUMN} places the probe; "
            "leave out one of the two"
        )
    if PROBE_COLUMN in frame.columns:
        probe = numeric_column(frame, PROBE_COLUMN, label, allow_nonfinite=False)
    elif probe_x is not None:
        probe = np.full(run.n_samples, float(probe_x))
    else:
        probe = None
    reach = probe_reach_m(xs)
    for where, values in (("--probe-x", None if probe_x is None else np.array([probe_x])), (PROBE_COLUMN, probe)):
        outside = np.array([]) if values is None else np.flatnonzero(~((values >= 0) & (values <= reach)))
        if outside.size:
            at = f"row {outside[0] + 1}, column '{where}'" if where == PROBE_COLUMN else where
            raise InputError(
                f"{label}: {at}: a probe at {values[outside[0]]:g} m is off the screw (x from the source, "
                f"0…{reach:g} m: twice the furthest sensor)"
            )
    return ScrewRun(
        name=run_name,
        source=label,
        time=run.time - run.time[0],
        names=tuple(order),
        positions=xs,
        rises=run.temps - ambient,
        ambient=ambient,
        error=run.error,
        probe_x=probe,
        run=run,
    )


def probe_reach_m(positions) -> float:
    """The farthest a probe may be from the source (m): twice the furthest sensor."""
    return 2.0 * float(np.max(positions))


def run_label(path) -> str:
    return Path(str(path)).stem
