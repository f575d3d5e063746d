"""A model's own held-out check: its error on held-out conditions or runs, input selection and the ridge penalty
chosen on them, and the over-fit warning.

``fit``, ``diagnose`` and ``sweep`` ask these questions through this module;
it imports none of them.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from groupfit.errors import InputError
from groupfit.heldout.design import group_design, group_index, group_sample_floor
from groupfit.heldout.folds import Folds, fold_columns, make_folds
from groupfit.heldout.records import OverfitCheck, RidgeScore, RidgeSetting
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.heldout.selection import select_sensors
from groupfit.models.ridge import check_ridge_alpha, choose_ridge_alpha

OVERFIT_RATIO = 3.0
"""The base model is called over-fitted when its held-out RMS exceeds its in-sample RMS by this factor."""


def select_inputs(
    X: np.ndarray,
    y: np.ndarray,
    names: Sequence[str],
    frames: Sequence[pd.DataFrame],
    exclude: set[str],
    method: str,
    k: int | None = None,
    *,
    splits: list | None = None,
) -> tuple[list[str], Folds]:
    """The inputs ``method`` chooses among ``names`` (columns of X), scored on held-out conditions or runs.

    ``frames`` are the runs' tables (stacked in the order of X's rows); the
    folds come from their operating columns, the columns not in ``exclude``.
    ``splits``: other ``(train, test)`` row indices over the measured rows
    (e.g. :func:`groupfit.heldout.nextrun.next_run_splits`) to score on instead.
    """
    folds = held_out_folds(frames, exclude, y)
    rows = np.isfinite(y)
    splits = folds.index_splits() if splits is None else splits
    return select_sensors(X[rows], y[rows], list(names), method, k, splits=splits), folds


def held_out_folds(frames: Sequence[pd.DataFrame], exclude: set[str], y: np.ndarray) -> Folds:
    """The diagnosis's held-out folds over the runs' rows with a measured error ``y``."""
    columns = fold_columns(pd.concat(list(frames), ignore_index=True), exclude)
    return make_folds(list(frames), columns).restricted(np.isfinite(y))


def held_out_check(
    X: np.ndarray,
    y: np.ndarray,
    frames: Sequence[pd.DataFrame],
    exclude: set[str],
    *,
    fit_intercept: bool = True,
    ridge_alpha: float = 0.0,
    grouped: dict[str, Any] | None = None,
) -> OverfitCheck | None:
    """A model's RMS in sample and on the diagnosis's held-out folds; None with fewer than two folds.

    The rows with a measured error ``y`` are fitted and scored; a global model is fitted as ``fit --p 0``
    fits it (least squares, or the ridge penalty ``ridge_alpha``). ``grouped``: the model file (as a dict)
    of a grouped model on a fully measured run, its groups refitted on each fold with the breaks kept
    and scored where they keep enough samples (:meth:`Folds.within_groups`).
    """
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
    return overfit_check(scorer, folds, grouped=grouped is not None)


def ridge_setting(
    option: float | str,
    p: int,
    X: np.ndarray,
    y: np.ndarray,
    frames: Sequence[pd.DataFrame],
    exclude: set[str],
    *,
    fit_intercept: bool = True,
    default: bool = False,
) -> RidgeSetting:
    """The penalty of ``--ridge ALPHA|auto`` for a global model, and how it was found.

    ``auto``: the penalty with the least error on held-out operating conditions or runs (the rows with a
    measured error ``y``), ties to the smaller one. Held-out conditions, not the forward chaining that
    chooses p: a later segment of the same programme keeps the collinear inputs' pattern, so cancelling
    coefficients still hold there; a condition the fit never saw breaks the pattern, as a next run does
    (``bench/bench_next_run.py``). ``default``: the penalty was chosen without ``--ridge`` (``fit``'s
    default for a global model whose p it chose).
    """
    if p != 0:
        raise InputError(
            f"--ridge with p = {p}: the ridge penalty is for one global model (--p 0) on many collinear "
            "inputs; a grouped model's groups are fitted by least squares"
        )
    if option != "auto":
        return RidgeSetting(check_ridge_alpha(option), "given")
    rows = np.isfinite(y)
    folds = held_out_folds(frames, exclude, y)
    alpha, table = choose_ridge_alpha(X[rows], y[rows], folds.index_splits(), fit_intercept=fit_intercept)
    scores = tuple(RidgeScore(row["alpha"], row["held_out_rms_um"]) for row in table)
    return RidgeSetting(alpha, "held-out", scores, folds.describe(), default=default)


def overfit_check(scorer: HeldOutScorer, folds: Folds, *, grouped: bool = False) -> OverfitCheck:
    """The model's own regression: in-sample RMS against held-out RMS on the folds, and what to do about it.

    A grouped model's groups are stretches of the modelling run: a held-out fold that takes most of a
    group leaves that group's coefficients with little to be fitted on, so fewer groups is advised too.
    """
    in_sample, held_out = scorer.in_sample_rms, scorer.held_out_rms
    advice = "start from a selected model (groupfit fit --select forward, or diagnose --select forward)"
    if grouped:
        advice = "refit with fewer groups (groupfit fit --p 0) or " + advice
    return OverfitCheck(
        in_sample_rms_um=in_sample,
        held_out_rms_um=held_out,
        folds=folds.describe(),
        overfitted=bool(held_out > OVERFIT_RATIO * max(in_sample, 1e-12)),
        grouped=grouped,
        advice=advice,
    )
