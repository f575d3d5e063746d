"""The model ``fit`` would write, in ``compare``: its global model as ``fit`` fits it, scored as ``replay`` scores it.

``compare`` marks the p ``fit`` would choose. When that is the global model
(p = 0), ``fit`` does not write the least-squares MLR that ``compare``
scores: it fits it with the ridge penalty of least held-out error
(:mod:`groupfit.heldout.penalty`) and may add a fast-response stage of the
inputs' swings (:mod:`groupfit.fast_response_choice`). This module builds
that model file as ``fit`` builds it from the same modelling runs, and
scores it on every run through the run-time rule, sample by sample
(:func:`groupfit.rule_faults.replayed_prediction`), so that its figure on a
validation run is ``groupfit replay``'s of ``fit``'s model file on that run
(``compare``'s column "fit's model", the rows ``"model": "fit"`` of
``--json``).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from groupfit.data import Run
from groupfit.fast_response import describe, stage_of
from groupfit.fast_response_choice import choose_stage
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor
from groupfit.rule_faults import replayed_prediction
from groupfit.search.base import SearchSettings

FIT_KEY = "fit"
"""The key of fit's model among compare's predictions and in its rows' ``model``."""


def fit_model_file(
    parts: Sequence[Run],
    modelling: Run,
    measured: Run,
    *,
    ridge_alpha: float,
    n: int,
    c: float,
    fit_intercept: bool,
    objective: str,
    search: SearchSettings,
) -> ModelFile:
    """The global model file ``fit`` writes for the modelling runs ``parts`` (joined: ``modelling``; its rows with
    a measured error: ``measured``): fitted with ``ridge_alpha``, its recalibration and fast-response stage chosen
    on the runs' held-out stretches (``fit --recalibrate auto``)."""
    settings = dict(n=n, c=c, objective=objective, fit_intercept=fit_intercept, search=search)
    estimator = GroupedRegressor.from_settings(p=0, **settings)
    estimator.set_params(ridge_alpha=ridge_alpha)
    estimator.fit(measured.temps, measured.error)
    model = estimator.to_model_file(modelling)
    model, tuning, _ = choose_stage(model, [(part.frame, part.error) for part in parts], "auto")
    return model.replace(recalibration=tuning.section)


def differs_from_mlr(model: ModelFile) -> bool:
    """Whether fit's global model is another than the least-squares MLR: a ridge penalty, or a fast-response stage."""
    return bool(model.ridge_alpha) or stage_of(model) is not None


def fit_model_summary(model: ModelFile) -> dict[str, Any]:
    """What fit's model is (``compare --json``: ``fit_model``)."""
    stage = stage_of(model)
    return {
        "p": int(model.p),
        "ridge_alpha": float(model.ridge_alpha or 0.0),
        "fast_response": None if stage is None else describe(stage),
        "scored": "through the run-time rule, as replay scores the model file fit writes",
    }


def fit_model_line(model: ModelFile) -> str:
    """``compare``'s line on the column "fit's model"."""
    stage = stage_of(model)
    what = [f"ridge penalty alpha = {model.ridge_alpha:g}"] if model.ridge_alpha else ["least squares"]
    what += [describe(stage)] if stage is not None else []
    return (
        f"fit's model (its column above): fit's choice p = 0 as fit writes it ({'; '.join(what)}), scored on "
        "each run as replay scores that model file"
    )


def modelling_prediction(model: ModelFile, parts: Sequence[Run]) -> np.ndarray:
    """Fit's model on its modelling runs, each replayed from its start, end to end."""
    return np.concatenate([replayed_prediction(model, part)[0] for part in parts])


__all__ = [
    "FIT_KEY",
    "differs_from_mlr",
    "fit_model_file",
    "fit_model_line",
    "fit_model_summary",
    "modelling_prediction",
]
