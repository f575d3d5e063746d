"""Start a diagnosis from a selected model: the model's inputs re-chosen on held-out conditions.

A model with many collinear sensors fits its modelling run closely and the
next run badly; on it, even an out-of-sample score of a candidate effect is
unreliable, because every refit moves all the collinear coefficients. Choosing
the inputs first, by the same held-out folds the diagnosis uses (whole
conditions or whole runs), gives it a base that generalises.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from groupfit.data import Run
from groupfit.diagnose.augment import refit_model
from groupfit.diagnose.candidates import usable_columns
from groupfit.diagnose.folds import Folds, make_folds
from groupfit.diagnose.residual import model_inputs
from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.sweep.selection import select_sensors


def select_inputs(
    X: np.ndarray,
    y: np.ndarray,
    names: Sequence[str],
    frames: Sequence[pd.DataFrame],
    exclude: set[str],
    method: str,
    k: int | None = None,
) -> tuple[list[str], Folds]:
    """The inputs ``method`` chooses among ``names`` (columns of X), scored on held-out conditions or runs.

    ``frames`` are the runs' tables (stacked in the order of X's rows); the
    folds come from their operating columns, the columns not in ``exclude``.
    """
    folds = held_out_folds(frames, exclude, y)
    rows = np.isfinite(y)
    return select_sensors(X[rows], y[rows], list(names), method, k, splits=folds.index_splits()), folds


def held_out_folds(frames: Sequence[pd.DataFrame], exclude: set[str], y: np.ndarray) -> Folds:
    """The diagnosis's held-out folds over the runs' rows with a measured error ``y``."""
    columns, _ = usable_columns(pd.concat(list(frames), ignore_index=True), exclude)
    return make_folds(list(frames), columns).restricted(np.isfinite(y))


def held_out_check(
    X: np.ndarray,
    y: np.ndarray,
    frames: Sequence[pd.DataFrame],
    exclude: set[str],
    fit_intercept: bool = True,
    ridge_alpha: float = 0.0,
    grouped: dict[str, Any] | None = None,
) -> dict[str, Any] | None:
    """A model's RMS in sample and on the diagnosis's held-out folds; None with fewer than two folds.

    The rows with a measured error ``y`` are fitted and scored; a global model is fitted as ``fit --p 0``
    fits it (least squares, or the ridge penalty ``ridge_alpha``). ``grouped``: the model file (as a dict)
    of a grouped model on a fully measured run, its groups refitted on each fold with the breaks kept
    and scored where they keep enough samples (:meth:`Folds.within_groups`). ``overfitted`` is the
    diagnosis's warning.
    """
    from groupfit.diagnose.candidates import HeldOutScorer
    from groupfit.diagnose.design import group_design, group_index, group_sample_floor
    from groupfit.diagnose.loop import overfit_check

    rows = np.isfinite(y)
    folds = held_out_folds(frames, exclude, y)
    if grouped is not None:
        if not rows.all():
            return None
        folds = folds.within_groups(group_index(grouped, len(y)), group_sample_floor(grouped, effects=0))
    if folds.n_folds < 2:
        return None
    if grouped is not None:
        design = group_design(grouped, X)
    else:
        design = np.column_stack([np.ones(int(rows.sum())), X[rows]]) if fit_intercept else X[rows]
    scorer = HeldOutScorer(y[rows], design, folds, ridge_alpha=ridge_alpha, fit_intercept=fit_intercept)
    return overfit_check(scorer, folds, grouped is not None)


def ridge_setting(
    option: float | str,
    p: int,
    X: np.ndarray,
    y: np.ndarray,
    frames: Sequence[pd.DataFrame],
    exclude: set[str],
    fit_intercept: bool = True,
) -> dict[str, Any]:
    """The penalty of ``--ridge ALPHA|auto`` for a global model, and how it was found.

    ``auto``: the penalty with the least error on held-out conditions or runs, the rows with a measured
    error ``y``; the result then holds ``held_out`` (the held-out RMS of every penalty tried) and ``folds``.
    """
    from groupfit.models.ridge import check_ridge_alpha, choose_ridge_alpha

    if p != 0:
        raise InputError(
            f"--ridge with p = {p}: the ridge penalty is for one global model (--p 0) on many collinear "
            "inputs; a grouped model's groups are fitted by least squares"
        )
    if option != "auto":
        return {"alpha": check_ridge_alpha(option), "chosen": "given"}
    folds = held_out_folds(frames, exclude, y)
    rows = np.isfinite(y)
    alpha, table = choose_ridge_alpha(X[rows], y[rows], folds.index_splits(), fit_intercept)
    return {"alpha": alpha, "chosen": "held-out", "held_out": table, "folds": folds.describe()}


def ridge_base_model(model: dict[str, Any], runs: Sequence[Run], alpha: float | str) -> tuple[dict[str, Any], dict]:
    """The global model refitted with a ridge penalty (``"auto"``: chosen on held-out conditions or runs)."""
    inputs = [model_inputs(model, run) for run in runs]
    exclude = {runs[0].time_name, model["error"], *model["temps"]}
    y = np.concatenate([run.error for run in runs])
    frames = [run.frame for run in runs]
    info = ridge_setting(alpha, model["p"], np.vstack(inputs), y, frames, exclude, model["intercept"])
    ridged = ModelFile.coerce(dict(model, ridge_alpha=info["alpha"] or None))
    return refit_model(ridged, list(runs), inputs, ridged.temps, ridged.derived_inputs or ()), info


def select_base_model(model: dict[str, Any], runs: Sequence[Run], method: str) -> tuple[dict[str, Any], dict]:
    """The model refitted on the inputs chosen by ``method``; and what was chosen."""
    derived = {d["name"] for d in model.get("derived_inputs", [])}
    if derived:
        raise InputError("--select re-chooses measured inputs; this model already has derived inputs: select first")
    inputs = [model_inputs(model, run) for run in runs]
    exclude = {runs[0].time_name, model["error"], *model["temps"]}
    frames = [run.frame for run in runs]
    y = np.concatenate([run.error for run in runs])
    names, folds = select_inputs(np.vstack(inputs), y, model["temps"], frames, exclude, method)
    keep = [model["temps"].index(name) for name in names]
    selected = refit_model(model, list(runs), [x[:, keep] for x in inputs], names, [])
    return selected, {"method": method, "inputs": names, "folds": folds.describe()}
