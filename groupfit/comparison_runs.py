"""Every compared model on every run: its predictions, prediction bands and scored rows.

On the modelling run each model serves by sample index (fit's model replayed
on each modelling run, :mod:`groupfit.comparison_fit`); on a validation run
the grouped models serve through the run-time rule's groups with its
bumpless transfer, and fit's model is replayed by its rule, with the
recording the run continues in front. Every run is scored on its samples
with a measured error and a prediction (none where the rule is in sensor
fault: :mod:`groupfit.comparison_faults`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from groupfit.comparison_ar1 import ar1_prediction
from groupfit.comparison_faults import model_label
from groupfit.comparison_fit import FIT_KEY, modelling_prediction
from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.inference.prediction import band_for
from groupfit.metrics import error_metrics, prediction_accuracy
from groupfit.model import ModelFile
from groupfit.models.ar1 import AR1Model
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.mlr import MLR
from groupfit.rule_faults import replayed_prediction


@dataclass(frozen=True)
class FittedModels:
    """The models ``compare`` fitted on the modelling run, and the model files the run-time rule replays."""

    mlr: MLR
    ar1: AR1Model | None
    grouped: dict[int, GroupedRegressor]
    files: dict[str, ModelFile]
    """By prediction key: the MLR's model file (as ``fit --p 0`` writes it), each grouped model's, and fit's
    model's when it is another than the MLR (:mod:`groupfit.comparison_fit`)."""


def distance_to_change(breaks: list[int], changes: list[int]) -> list[int | None]:
    """Each break's distance in samples to the nearest change of operating condition."""
    if not changes:
        return [None] * len(breaks)
    return [int(min(abs(b - c) for c in changes)) for b in breaks]


def modelling_predictions(
    models: FittedModels, parts: Sequence[Run], modelling: Run, settings
) -> tuple[dict[str, np.ndarray], dict[str, tuple]]:
    """Every model on the modelling run (``parts`` joined; grouped models by sample index, fit's model replayed
    on each part), and the prediction bands of the MLR and the grouped models. ``settings``: the
    :class:`~groupfit.comparison.ComparisonSettings` (the AR(1) model's start and inputs)."""
    preds = {"mlr": models.mlr.predict(modelling.temps)}
    if models.ar1 is not None:
        preds["ar1"] = ar1_prediction(models.ar1, modelling, modelling, settings)
    bands = {"mlr": tuple(models.mlr.prediction_interval(modelling.temps).T)}
    for p, model in models.grouped.items():
        preds[f"grouped{p}"] = model.predict(modelling.temps)
        bands[f"grouped{p}"] = band_for(model, modelling.temps, preds[f"grouped{p}"])
    if FIT_KEY in models.files:
        preds[FIT_KEY] = modelling_prediction(models.files[FIT_KEY], parts)
    return preds, bands


def validation_predictions(
    models: FittedModels, whole: Run, run: Run, modelling: Run, settings, live_rule
) -> tuple[dict[str, np.ndarray], dict[str, tuple]]:
    """Every model on a validation run, untouched (``whole``: the run with the recording it continues in front):
    grouped models through ``live_rule`` when given, fit's model replayed by its rule; and the bands. A sample
    with an input that is not a number gets none (NaN): :mod:`groupfit.comparison_faults` replays it.
    ``settings`` as :func:`modelling_predictions` takes them."""
    read = np.isfinite(run.temps).all(axis=1)
    temps = np.where(np.isfinite(run.temps), run.temps, 0.0)  # the estimators take finite values only
    preds = {"mlr": np.where(read, models.mlr.predict(temps), np.nan)}
    if models.ar1 is not None:
        preds["ar1"] = ar1_prediction(models.ar1, run, modelling, settings, next_run=True)
    bands = {"mlr": tuple(np.where(read[:, None], models.mlr.prediction_interval(temps), np.nan).T)}
    skip = whole.n_samples - run.n_samples
    for p, model in models.grouped.items():
        key, groups = f"grouped{p}", None
        if live_rule is None:
            preds[key] = np.where(read, model.predict(temps), np.nan)
        else:
            groups = live_rule(models.files[key], whole.temps)  # the rule's groups and its bumpless transfer
            preds[key] = models.files[key].predict(whole.temps, groups, transfer=True)[skip:]
            groups = groups[skip:]
        band = band_for(model, temps, preds[key], groups)
        bands[key] = band if band is None else tuple(np.where(read, end, np.nan) for end in band)
    if FIT_KEY in models.files:
        preds[FIT_KEY] = replayed_prediction(models.files[FIT_KEY], whole, skip)[0]
    return preds, bands


def scored_rows(
    run: Run,
    preds: Mapping[str, np.ndarray],
    grouped: Mapping[int, GroupedRegressor],
    changes: list[int] | None,
    fit_model: ModelFile | None,
) -> list[dict[str, Any]]:
    """One row per model on ``run``: RMS, R and max |e| on the samples with a measured error and a prediction
    (not in sensor fault), the accuracy; for the modelling run (``changes`` given) each break's distance to the
    nearest change of operating condition; fit's model's row with its ridge penalty."""
    rows = []
    for key, prediction in preds.items():
        residual = run.error - prediction
        if not np.isfinite(residual).any():
            raise InputError(
                f"{run.source}: no sample of it is left to score {model_label(key)} on: the run-time rule is in "
                "sensor fault wherever the error is measured (a reading that is not a number, or outside its valid "
                "range, for longer than its hold); repair those readings or leave the run out"
            )
        metrics = error_metrics(residual[np.isfinite(residual)])
        if key.startswith("grouped"):
            p = int(key[len("grouped") :])
            breaks = grouped[p].breaks_
            row = {"model": "grouped", "p": p, "breaks": breaks}
            row["break_distance"] = distance_to_change(breaks, changes) if changes is not None else None
        else:
            row = {"model": key, "p": None if key == "ar1" else 0, "breaks": None, "break_distance": None}
        if key == FIT_KEY:
            row["ridge_alpha"] = float(fit_model.ridge_alpha or 0.0)
        accuracy = prediction_accuracy(run.error, residual)
        row.update({"run": run.name, **metrics, "accuracy_percent": accuracy, "R_mm": metrics["R_um"] / 1000.0})
        rows.append(row)
    return rows


__all__ = [
    "FittedModels",
    "distance_to_change",
    "modelling_predictions",
    "scored_rows",
    "validation_predictions",
]
