"""A run's operating conditions as ``compare`` reads them: where they change, and whether a run repeats the
modelling run's duty cycle."""

from __future__ import annotations

import numpy as np

from groupfit.data import Run
from groupfit.errors import InputError


def condition_changes(run: Run, columns: tuple[str, ...]) -> list[int]:
    """Samples (1-based) after which an operating-condition column changes value."""
    changes: set[int] = set()
    for column in columns:
        if column not in run.frame.columns:
            raise InputError(f"{run.source}: condition column '{column}' not found; set [compare] conditions")
        values = run.frame[column].to_numpy()
        changes.update((np.flatnonzero(values[1:] != values[:-1]) + 1).tolist())
    return sorted(changes)


def condition_levels(run: Run, columns: tuple[str, ...]) -> tuple[list[tuple], list[int]]:
    """The sequence of operating-condition levels of a run and the samples (1-based) after which each ends."""
    values = [tuple(row) for row in run.frame[list(columns)].to_numpy().tolist()] if columns else []
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
    if levels != model_levels:
        return "other condition"
    if any(abs(a - b) > tolerance for a, b in zip(ends, model_ends)):
        return "other condition"
    return "same condition"


__all__ = ["condition_changes", "condition_levels", "run_condition"]
