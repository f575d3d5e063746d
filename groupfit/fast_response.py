"""The model's response to fast swings of its sensors, fitted apart: a stage for a compensation with probe checks.

A model fitted over a long run weighs each sensor by what moves the error
over hours. Faster swings of the same sensors (a chiller cycling, a coolant
pump, a door) move the error with other weights; what the model leaves of
them changes within minutes, and between two probe checks no filter can
follow it. This stage fits that response apart. Its inputs are the model's
measured inputs less their own low-pass, ``h_k = T_k − LP_τ(T_k)``, fitted by
least squares on the residual the model leaves on its modelling runs, the
model's own coefficients kept. A swing's high-pass returns to zero, so the
stage leaves the model's level, which the next-run estimate judges, alone.

The stage is written as one low-pass derived input per sensor: the sensor's
coefficient raised by ``g_k``, the low-pass's coefficient ``−g_k``; every
target computes it as any derived input. The model file records it under
``training.fast_response`` (τ, the sensors, ``g`` and the sensors' own
slopes), so that the model without it is recovered exactly (:func:`without_stage`) before the model is changed
(``diagnose``) and the stage chosen again.

Whether a model keeps the stage, and with which τ, is decided on held-out
stretches with simulated checks (:mod:`groupfit.fast_response_choice`).
On absolute readings or over a reference column (``u_k = T_k − R``: the
stage adds the reference's low-pass too); a grouped model fitted on one run
takes one set of gains shared by its groups, fitted on the residual of each
sample's offline group, each group's own slopes recorded. A reference taken
at the start, a position or a dead band are left as they are.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Mapping, Sequence

import numpy as np

from groupfit.features import derived_matrix
from groupfit.model import ModelFile
from groupfit.reference import START
from groupfit.training_checks import FAST_KEY, slopes_per_group, stage_features


def stage_columns(model: ModelFile) -> list[str]:
    """The measured inputs a stage may be fitted on (empty: the model cannot take one)."""
    if model.reference == START or model.position is not None or model.dead_band is not None:
        return []
    return list(model.measured_inputs)


def stage_of(model: ModelFile) -> Mapping[str, Any] | None:
    """The model's recorded stage, or None."""
    return (model.training or {}).get(FAST_KEY)


def without_stage(model: ModelFile) -> ModelFile:
    """The model as it was before its stage was added (itself when it has none)."""
    stage = stage_of(model)
    if stage is None:
        return model
    names = {feature.name for feature in _features(stage)}
    offset = 1 if model.intercept else 0
    keep = [j for j, name in enumerate(model.temps) if name not in names]
    rows = []
    for row, row_slopes in zip(model.coefficients, group_slopes(stage, len(model.coefficients))):
        slopes = dict(zip(stage["columns"], row_slopes))
        rows.append((*row[:offset], *(slopes.get(model.temps[j], row[offset + j]) for j in keep)))
    derived = tuple(f for f in model.derived_inputs or () if f.name not in names)
    training = {k: v for k, v in (model.training or {}).items() if k != FAST_KEY}
    return model.replace(
        switching=_ranges_kept(model, keep),
        temps=tuple(model.temps[j] for j in keep),
        coefficients=tuple(rows),
        derived_inputs=derived or None,
        training=training,
    )


def group_slopes(stage: Mapping[str, Any], n_groups: int) -> list[list[float]]:
    """The sensors' slopes without the stage, one list per coefficient row: ``slopes`` holds one list per group
    in a grouped model, the single list of a global model's one row otherwise."""
    slopes = stage["slopes"]
    return [list(row) for row in slopes] if slopes_per_group(slopes) else [list(slopes)] * n_groups


def _features(stage: Mapping[str, Any]):
    return stage_features(stage["columns"], stage["tau_s"], stage.get("reference"))


def _ranges_added(model: ModelFile, columns: Sequence[str]):
    """The switching section with a range for each of the stage's low-passes: its sensor's (the reference's
    low-pass: the widest of them). Only the measured inputs' ranges are read at run time."""
    switching = model.switching
    index = [model.temps.index(column) for column in columns]
    low = [switching.temp_min_c[j] for j in index]
    high = [switching.temp_max_c[j] for j in index]
    if model.reference is not None:
        low, high = [*low, min(low)], [*high, max(high)]
    return dataclasses.replace(
        switching, temp_min_c=(*switching.temp_min_c, *low), temp_max_c=(*switching.temp_max_c, *high)
    )


def _ranges_kept(model: ModelFile, keep: Sequence[int]):
    """The switching section with the valid ranges of the inputs ``keep`` only."""
    switching = model.switching
    low = tuple(switching.temp_min_c[j] for j in keep)
    high = tuple(switching.temp_max_c[j] for j in keep)
    return dataclasses.replace(switching, temp_min_c=low, temp_max_c=high)


def high_passes(
    model: ModelFile, frame, columns: Sequence[str], tau_s: float, inputs: np.ndarray | None = None
) -> np.ndarray:
    """``u_k − LP_τ(u_k)`` of the inputs ``columns`` on one run, ``u_k`` as the model reads it (``T_k``, or
    ``T_k − R`` over a reference column ``R``: then ``(T_k − R) − LP(T_k) + LP(R)``, the low-pass being
    linear), the low-passes as every target computes them. ``inputs``: the model's inputs on the run, when
    already computed."""
    features = stage_features(columns, tau_s, model.reference)
    lowpassed = derived_matrix(features, frame, model.sampling_period_s)
    inputs = model.inputs(frame) if inputs is None else inputs
    high = inputs[:, [model.temps.index(column) for column in columns]] - lowpassed[:, : len(columns)]
    return high + lowpassed[:, len(columns) :] if model.reference is not None else high


def stage_split(model: ModelFile) -> tuple[list[int], np.ndarray] | None:
    """The positions among the model's inputs of those without the stage, and the matrix that maps the model's
    inputs to the stage's high-passes (None: no stage)."""
    stage = stage_of(model)
    if stage is None:
        return None
    names = [f.name for f in _features(stage)]
    base = [j for j, name in enumerate(model.temps) if name not in names]
    k = len(stage["columns"])
    mapping = np.zeros((len(model.temps), k))
    for i, column in enumerate(stage["columns"]):
        mapping[model.temps.index(column), i] = 1.0
        mapping[model.temps.index(names[i]), i] = -1.0
        if len(names) > k:  # the reference's low-pass
            mapping[model.temps.index(names[k]), i] = 1.0
    return base, mapping


def fit_gains(high_pass: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Least squares of the residual on the high-passes, over the rows with a measured residual."""
    rows = np.isfinite(residual) & np.all(np.isfinite(high_pass), axis=1)
    return np.linalg.lstsq(high_pass[rows], residual[rows], rcond=None)[0]


def with_stage(model: ModelFile, runs: Sequence, tau_s: float) -> ModelFile | None:
    """``model`` (without a stage) with the stage of time constant ``tau_s`` fitted on ``runs`` ((frame, error)
    pairs); None when the model cannot take one or the runs are too short for it."""
    columns = stage_columns(model)
    if not columns or (model.p > 0 and len(runs) != 1):  # a grouped model's groups are those of its one run
        return None
    high, residual = [], []
    for frame, error in runs:
        inputs = model.inputs(frame)
        residual.append(np.asarray(error, dtype=float) - model.predict(inputs))
        high.append(high_passes(model, frame, columns, tau_s, inputs))
    high, residual = np.vstack(high), np.concatenate(residual)
    if np.count_nonzero(np.isfinite(residual)) < 4 * (len(columns) + 1):
        return None
    gains = fit_gains(high, residual)
    if not np.all(np.isfinite(gains)):
        return None
    features = stage_features(columns, tau_s, model.reference)
    offset = 1 if model.intercept else 0
    index = [offset + model.temps.index(column) for column in columns]
    rows, slopes = [], []
    for coefficients in model.coefficients:
        row = list(coefficients)
        slopes.append([float(row[j]) for j in index])
        for j, gain in zip(index, gains):
            row[j] += float(gain)
        row += [-float(gain) for gain in gains]
        if model.reference is not None:
            row.append(float(np.sum(gains)))
        rows.append(tuple(row))
    stage = {
        "tau_s": float(tau_s),
        "columns": list(columns),
        "coefficients": [float(g) for g in gains],
        "slopes": slopes[0] if len(slopes) == 1 else slopes,
        **({"reference": model.reference} if model.reference is not None else {}),
    }
    return model.replace(
        switching=_ranges_added(model, columns),
        temps=(*model.temps, *(f.name for f in features)),
        coefficients=tuple(rows),
        derived_inputs=(*(model.derived_inputs or ()), *features),
        training={**(model.training or {}), FAST_KEY: stage},
    )


def describe(stage: Mapping[str, Any]) -> str:
    return (
        f"fast response: each of {len(stage['columns'])} input(s) less its {stage['tau_s'] / 60:g}-min low-pass, "
        "fitted on the model's residual (the model's coefficients kept)"
    )


__all__ = [
    "FAST_KEY",
    "describe",
    "fit_gains",
    "group_slopes",
    "high_passes",
    "stage_columns",
    "stage_of",
    "stage_split",
    "with_stage",
    "without_stage",
]
