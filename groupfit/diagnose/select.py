"""Start a diagnosis from a selected model: the model's inputs re-chosen on held-out conditions.

A model with many collinear sensors fits its modelling run closely and the
next run badly; on it, even an out-of-sample score of a candidate effect is
unreliable, because every refit moves all the collinear coefficients. Choosing
the inputs first, by the same held-out folds the diagnosis uses (whole
conditions or whole runs), gives it a base that generalises.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from groupfit.data import Run
from groupfit.diagnose.augment import refit_model
from groupfit.diagnose.residual import ModelLike, model_inputs
from groupfit.diagnose.result import InputSelection
from groupfit.errors import InputError
from groupfit.heldout.check import ridge_setting, select_inputs
from groupfit.heldout.records import RidgeSetting
from groupfit.model import ModelFile


def ridge_base_model(model: ModelLike, runs: Sequence[Run], alpha: float | str) -> tuple[ModelFile, RidgeSetting]:
    """The global model refitted with a ridge penalty (``"auto"``: chosen on held-out conditions or runs)."""
    model = ModelFile.coerce(model)
    inputs = [model_inputs(model, run) for run in runs]
    exclude = {runs[0].time_name, model.error, *model.temps}
    y = np.concatenate([run.error for run in runs])
    frames = [run.frame for run in runs]
    info = ridge_setting(alpha, model.p, np.vstack(inputs), y, frames, exclude, fit_intercept=model.intercept)
    if not info.alpha:  # no penalty: the model as given
        return model, info
    ridged = model.replace(ridge_alpha=info.alpha or None)
    return refit_model(ridged, list(runs), inputs, ridged.temps, ridged.derived_inputs or ()), info


def select_base_model(model: ModelLike, runs: Sequence[Run], method: str) -> tuple[ModelFile, InputSelection]:
    """The model refitted on the inputs chosen by ``method``; and what was chosen."""
    model = ModelFile.coerce(model)
    derived = {feature.name for feature in model.derived_inputs or ()}
    if derived:
        raise InputError("--select re-chooses measured inputs; this model already has derived inputs: select first")
    inputs = [model_inputs(model, run) for run in runs]
    exclude = {runs[0].time_name, model.error, *model.temps}
    frames = [run.frame for run in runs]
    y = np.concatenate([run.error for run in runs])
    names, folds = select_inputs(np.vstack(inputs), y, list(model.temps), frames, exclude, method)
    keep = [model.temps.index(name) for name in names]
    selected = refit_model(model, list(runs), [x[:, keep] for x in inputs], names, [])
    return selected, InputSelection(method, tuple(names), len(model.temps), folds.describe())
