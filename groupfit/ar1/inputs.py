"""The inputs of ``compare``'s AR(1) model from a run: the heat column (and a structural sensor), read on
every row or refused naming the first row without a reading; on a validation run (:func:`next_run_inputs`)
a missed heat reading is kept, and the AR(1) routine holds its state there (:mod:`groupfit.ar1.rule`)."""

from __future__ import annotations

import numpy as np

from groupfit.data import Run, numeric_column
from groupfit.errors import InputError
from groupfit.fault_codes import refuse_implausible_temperature
from groupfit.reference import column_role
from groupfit.resample import GAP_PERIODS
from groupfit.setting_levels import is_setting
from groupfit.switching_checks import RULE_LIMIT

COMPARE_TODO = "or leave the AR(1) model out with --heat none"


def check_heat(heat: np.ndarray, *, source: str, name: str) -> None:
    """Refuse a heat reading that is not finite, below 0 or beyond :data:`RULE_LIMIT`, naming its row (1-based)
    and column."""
    heat = np.asarray(heat, dtype=float)
    bad = np.flatnonzero(~np.isfinite(heat) | (heat < 0) | (heat > RULE_LIMIT))
    if bad.size:
        raise InputError(
            f"{source}: row {int(bad[0]) + 1}, column '{name}' = {float(heat[bad[0]]):g}: the heat reading must be "
            f"a finite number from 0 to {RULE_LIMIT:g} (a speed logged with its sense of rotation: log its size)"
        )


def check_heat_setting(heat: np.ndarray, *, source: str, name: str, todo: str) -> None:
    """Refuse a heat column the AR(1) model cannot take: one that is 0 throughout (no heat to fit), or one that
    moves like a measurement rather than a setting held at a few levels (it would get one C2 per reading).
    ``todo``: what else to do, after binning the column."""
    heat = np.asarray(heat, dtype=float)
    if not np.any(heat > 0):
        raise InputError(
            f"{source}: heat column '{name}' is 0 on every row: the AR(1) model has no heat input to fit; name the "
            f"heat input (a speed, a power) with --heat COLUMN, {todo}"
        )
    moving = moves_like_measurement(heat, name)
    if moving:
        raise InputError(
            f"{source}: {moving}: the AR(1) model fits one C2 per heat level, so its heat input must be held at a "
            f"few set levels (a speed or power set-point); bin the column to its set levels, {todo}"
        )


def moves_like_measurement(heat: np.ndarray, name: str) -> str | None:
    """Words saying that a heat column moves like a measurement rather than a setting held at a few levels
    (:func:`groupfit.setting_levels.is_setting`); None when it is a setting."""
    heat = np.asarray(heat, dtype=float)
    if is_setting(heat):
        return None
    return f"heat column '{name}' moves like a measurement, not a setting ({len(np.unique(heat))} distinct readings)"


def refuse_heat_role(run: Run, heat: str, todo: str) -> None:
    """Refuse the run's error or time column as the heat input."""
    role = column_role(run, heat)
    if role:
        raise InputError(
            f"{run.source}: heat column '{heat}' is the run's {role}; name the heat level (a speed, a power) with "
            f"--heat COLUMN, {todo}"
        )


def heat_column(run: Run, heat: str) -> np.ndarray:
    """The heat level of ``compare``'s AR(1) model (a speed, a power, a heat flux): read on every row, ≥ 0."""
    values = read_on_every_row(run, heat_name(run, heat))
    check_heat(values, source=str(run.source), name=heat)
    return values


def heat_name(run: Run, heat: str) -> str:
    """``heat``, refused when ``run`` has no such column or it is the run's error or time."""
    if heat not in run.frame.columns:
        raise InputError(
            f"{run.source}: heat column '{heat}' for the AR(1) model not found; name it with --heat COLUMN "
            f"(or [compare] heat), {COMPARE_TODO}"
        )
    refuse_heat_role(run, heat, COMPARE_TODO)
    return heat


def read_on_every_row(run: Run, column: str) -> np.ndarray:
    """An input of the AR(1) model, refused naming the first row without a finite reading."""
    values = numeric_column(run.frame, column, str(run.source), allow_nonfinite=True)
    unread = np.flatnonzero(~np.isfinite(values))
    if unread.size:
        raise InputError(
            f"{run.source}: row {unread[0] + 1}, column '{column}' has no reading ({unread.size} row(s)); the AR(1) "
            f"model needs it on every row: fill it in, let --resample SECONDS interpolate up to {GAP_PERIODS} missed "
            "readings in a row, or leave the AR(1) model out with --heat none"
        )
    return values


def ar1_inputs(run: Run, heat: str, structural_sensor: str | None = None) -> np.ndarray:
    """The AR(1) model's inputs on a run it is fitted on: the heat column, then the structural sensor's."""
    return np.column_stack([heat_column(run, heat), *structural_column(run, structural_sensor)])


def structural_column(run: Run, structural_sensor: str | None) -> list[np.ndarray]:
    """The structural sensor's readings, read on every row (none without a structural sensor)."""
    if not structural_sensor:
        return []
    if structural_sensor not in run.frame.columns:
        raise InputError(f"{run.source}: structural sensor '{structural_sensor}' not found")
    return [temperature_on_every_row(run, structural_sensor)]


def temperature_on_every_row(run: Run, column: str) -> np.ndarray:
    """A temperature the AR(1) model reads beside its heat column (a structural or a rise sensor), refused
    naming the first row without a reading or with one outside the plausible range (a sensor's fault code,
    -999 °C, which a validation run keeps for the run-time rule of the other models to hold)."""
    values = read_on_every_row(run, column)
    what = f"the AR(1) model reads it on every row: fix those rows, {COMPARE_TODO}"
    refuse_implausible_temperature(values, column, str(run.source), what)
    return values


def next_run_inputs(run: Run, heat: str, structural_sensor: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The AR(1) model's inputs on a validation run, read as the AR(1) routine reads them, and where it holds its
    state: where the heat reading is missed (empty, NaN or ±inf; the heat column is 0 there, not read). A
    reading below 0 is refused as on the modelling run (:func:`check_heat`), and so is a heat column without a
    reading on any row, as a dead input is."""
    values = numeric_column(run.frame, heat_name(run, heat), str(run.source), allow_nonfinite=True)
    held = ~np.isfinite(values)
    if held.all():
        raise InputError(
            f"{run.source}: heat column '{heat}' has no reading on any row; the AR(1) model has nothing to run on: "
            f"fill it in, {COMPARE_TODO}"
        )
    values = np.where(held, 0.0, values)
    check_heat(values, source=str(run.source), name=heat)
    return np.column_stack([values, *structural_column(run, structural_sensor)]), held
