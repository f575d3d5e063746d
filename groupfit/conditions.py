"""A run's operating conditions as ``compare`` reads them: where they change, and whether a run repeats the
modelling run's duty cycle."""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.columns import usable_columns
from groupfit.data import Run
from groupfit.default_columns import SPEED_NAME as SPEED_NAME
from groupfit.errors import InputError
from groupfit.heldout.folds import operating_columns
from groupfit.setting_levels import setting_levels

LEVEL_TOLERANCE = 0.01
"""Two runs hold the same level of a condition column when their levels differ by at most this share."""


def run_operating_columns(runs: Sequence[Run]) -> list[str]:
    """The columns that set the first run's operating conditions (speeds, on/off of heat sources), found as
    ``fit``'s held-out check finds them, that every run holds."""
    first = runs[0]
    exclude = {first.time_name, first.error_name, *first.temp_names}
    if first.reference not in (None, "start"):
        exclude.add(first.reference)
    columns, _ = usable_columns(first.frame, exclude)
    found = operating_columns(first.frame, columns)
    return [c for c in found if all(c in run.frame.columns for run in runs[1:])]


def heat_level_column(operating: Sequence[str]) -> str | None:
    """The AR(1) model's heat level among a run's operating columns: the one named as a speed, else the
    only one; None when that does not decide it."""
    speeds = [c for c in operating if SPEED_NAME.search(str(c))]
    if len(speeds) == 1:
        return speeds[0]
    return operating[0] if not speeds and len(operating) == 1 else None


def condition_changes(run: Run, columns: tuple[str, ...]) -> list[int]:
    """Samples (1-based) after which an operating-condition column changes value (the ends of
    :func:`condition_levels`)."""
    for column in columns:
        if column not in run.frame.columns:
            raise InputError(f"{run.source}: condition column '{column}' not found; set [compare] conditions")
    return condition_levels(run, columns)[1]


def _levels_of(run: Run, column: str) -> np.ndarray:
    """A condition column's values, a number read back with noise as the levels it was set to
    (:func:`groupfit.setting_levels.setting_levels`)."""
    values = run.frame[column].to_numpy()
    numbers = pd.to_numeric(run.frame[column], errors="coerce").to_numpy(dtype=float)
    return setting_levels(numbers) if np.isfinite(numbers).all() else values


def condition_levels(run: Run, columns: tuple[str, ...]) -> tuple[list[tuple], list[int]]:
    """The sequence of operating-condition levels of a run and the samples (1-based) after which each ends."""
    values = list(zip(*(_levels_of(run, column).tolist() for column in columns))) if columns else []
    levels, ends = [], []
    for i, value in enumerate(values):
        if not levels or value != levels[-1]:
            if levels:
                ends.append(i)
            levels.append(value)
    return levels, ends


def run_condition(run: Run, modelling: Run, columns: tuple[str, ...], tolerance: int) -> str:
    """``"same condition"`` or ``"other condition"``: is ``run`` the modelling run's duty cycle again?

    Same condition: the condition columns (e.g. the spindle speed) go through the same levels in the same
    order, and each change comes within ``tolerance`` samples of the modelling run's: the paper's repeat of
    a working condition, with sampling moments that differ a little. The ambient and the machine's state at
    the start are not conditions: a repeat at another ambient or after a warm start is the same condition.
    """
    if not columns or any(c not in run.frame.columns for c in columns):
        return "other condition"
    levels, ends = condition_levels(run, columns)
    model_levels, model_ends = condition_levels(modelling, columns)
    if len(levels) != len(model_levels) or not all(map(_same_level, levels, model_levels)):
        return "other condition"
    if any(abs(a - b) > tolerance for a, b in zip(ends, model_ends)):
        return "other condition"
    return "same condition"


def _same_level(level: tuple, other: tuple) -> bool:
    """Two runs' levels of the condition columns: equal, numbers within :data:`LEVEL_TOLERANCE` (two runs'
    medians of a speed read back with noise differ a little)."""
    for a, b in zip(level, other):
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            if not np.isclose(a, b, rtol=LEVEL_TOLERANCE, atol=0.0):
                return False
        elif a != b:
            return False
    return True


__all__ = ["condition_changes", "condition_levels", "heat_level_column", "run_condition", "run_operating_columns"]
