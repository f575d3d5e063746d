"""The regressors of a model as the diagnosis fits it: groups by sample index, effects shared by every group.

A grouped model's measured inputs (and intercept) get their own columns in
each group. An effect the diagnosis adds (a derived input) gets one column,
and so one coefficient, for all groups: the candidates are scored that way
(:class:`groupfit.heldout.scorer.HeldOutScorer` adds one column to the
design), and the groups are refitted that way
(:func:`groupfit.diagnose.augment.fitted_groups`), so the model written is
the one that was scored. A coefficient per group would fit a slow effect on
each stretch of the run anew, from a fraction of its samples. A global model
(p = 0) has one group and is unchanged by this.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from groupfit.grouping import block_design, serving_group_index
from groupfit.model import ModelFile

ModelLike = ModelFile | Mapping[str, Any]
"""A model file, or its JSON object (read once, :meth:`ModelFile.coerce`)."""


def group_index(model: ModelLike, n_rows: int) -> np.ndarray:
    """The group serving each of ``n_rows`` samples of the modelling run, by sample index."""
    model = ModelFile.coerce(model)
    n_samples = n_rows if model.n_samples is None else int(model.n_samples)
    return serving_group_index(list(model.breaks), n_samples, model.n, n_rows)


def group_sample_floor(model: ModelLike, effects: int = 1) -> int:
    """c·M, M the coefficients of a group with ``effects`` more: a group is fitted on more samples than this."""
    model = ModelFile.coerce(model)
    n_coefficients = len(model.temps) + int(model.intercept) + effects  # temps names the derived inputs too
    return int(np.floor(float(model.c) * n_coefficients))


def shared_columns(model: ModelLike, names: Sequence[str] | None = None) -> np.ndarray:
    """Which of the inputs ``names`` (default: the model's) have one coefficient for every group.

    The derived inputs of a grouped model; none for a global model.
    """
    model = ModelFile.coerce(model)
    names = list(model.temps if names is None else names)
    if not model.breaks:
        return np.zeros(len(names), dtype=bool)
    derived = {feature.name for feature in model.derived_inputs or ()}
    return np.array([name in derived for name in names], dtype=bool)


def group_design(model: ModelLike, inputs: np.ndarray, shared: np.ndarray | None = None) -> np.ndarray:
    """The model's regressors: each group's measured inputs (and intercept) in its own columns, groups by
    sample index, then one column per shared input (``shared``, default :func:`shared_columns`)."""
    model = ModelFile.coerce(model)
    shared = shared_columns(model) if shared is None else np.asarray(shared, dtype=bool)
    groups = group_index(model, len(inputs))
    n_groups = len(model.breaks) + 1
    return block_design(inputs, groups, n_groups, fit_intercept=bool(model.intercept), shared=shared)


def stacked_design(model: ModelLike, inputs: Sequence[np.ndarray]) -> np.ndarray:
    """:func:`group_design` of each run's inputs, stacked."""
    model = ModelFile.coerce(model)
    return np.vstack([group_design(model, x) for x in inputs])
