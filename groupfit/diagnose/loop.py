"""The diagnosis loop: rank candidates, add the best while it is significant, report before/after."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from groupfit.data import Run
from groupfit.diagnose.augment import augment_model
from groupfit.diagnose.candidates import Candidate, candidate_features, rank_candidates, usable_columns
from groupfit.diagnose.checks import drift, ljung_box
from groupfit.diagnose.residual import LiveRule, model_inputs, residual
from groupfit.errors import InputError
from groupfit.grouping import serving_group_index
from groupfit.modelfile import error_metrics

MIN_SCORE = 0.3
"""Least fraction of the residual variance, out of sample, that makes an effect significant."""
MIN_EFFECT_RMS_UM = 0.1
"""Least residual RMS (µm) an effect must remove out of sample: below it, nothing a compensation would notice."""
MAX_EFFECTS = 3


@dataclass
class DiagnosisResult:
    """What the diagnosis found and did."""

    candidates: list[Candidate]
    added: list[Candidate]
    before: dict[str, Any]
    after: dict[str, Any]
    model: dict[str, Any]
    notes: list[str] = field(default_factory=list)
    checks_before: dict[str, Any] = field(default_factory=dict)
    checks_after: dict[str, Any] = field(default_factory=dict)
    residuals_before: dict[str, np.ndarray] = field(default_factory=dict)
    residuals_after: dict[str, np.ndarray] = field(default_factory=dict)


def check_inputs(model: dict[str, Any], run: Run, inputs: np.ndarray) -> list[str]:
    """Refuse runs whose model inputs cannot be evaluated; note dead-looking inputs."""
    notes = []
    for j, name in enumerate(model["temps"]):
        column = inputs[:, j]
        bad = ~np.isfinite(column)
        if bad.all():
            raise InputError(
                f"{run.source}: model input '{name}' has no finite value (a dead sensor): the model cannot be "
                "evaluated; replace the sensor or fit a model without it"
            )
        if bad.any():
            row = int(np.flatnonzero(bad)[0]) + 1
            raise InputError(
                f"{run.source}: model input '{name}' is not finite at row {row} ({int(bad.sum())} rows): "
                "repair or drop those rows before diagnosing"
            )
        if np.ptp(column) == 0.0:
            notes.append(f"model input '{name}' is constant on {run.name} (a dead sensor?)")
    return notes


def metrics_of(res: np.ndarray) -> dict[str, float]:
    return error_metrics(res[np.isfinite(res)])


def diagnose(
    model: dict[str, Any],
    data: Run,
    validate: Run | None = None,
    live_rule: LiveRule | None = None,
    min_score: float = MIN_SCORE,
    min_effect_rms_um: float = MIN_EFFECT_RMS_UM,
    max_effects: int = MAX_EFFECTS,
) -> DiagnosisResult:
    """Find what the model misses on ``data``, add it, and judge the result on ``validate``.

    Candidates are chosen on ``data`` only, by blocked cross-validation in
    time; ``validate`` is never used to choose, only to report.
    """
    inputs = model_inputs(model, data)
    notes = check_inputs(model, data, inputs)
    if validate is not None:
        notes += check_inputs(model, validate, model_inputs(model, validate))
    base_columns = {data.time_name, model["error"]}
    derived_sources = {d["column"] for d in model.get("derived_inputs", [])}
    used = set(model["temps"]) | derived_sources
    columns, column_notes = usable_columns(data.frame, exclude=base_columns | used)
    notes += column_notes
    measured_inputs = [t for t in model["temps"] if t in data.frame.columns]

    runs = {"data": data, **({"validate": validate} if validate is not None else {})}
    before = {key: residual(model, run, live_rule) for key, run in runs.items()}
    current_model, current_inputs = model, inputs
    current = dict(before)
    added: list[Candidate] = []
    first_ranking: list[Candidate] | None = None
    tried = candidate_features(columns, measured_inputs)
    while len(added) < max_effects:
        design = group_design(current_model, current_inputs)
        ranking = rank_candidates(data.error, data.frame, tried, model["sampling_period_s"], design)
        if first_ranking is None:
            first_ranking = ranking
        if not ranking:
            break
        best = ranking[0]
        if best.score < min_score or best.explained_rms_um < min_effect_rms_um:
            break
        current_model = augment_model(current_model, data, current_inputs, best.feature)
        current_inputs = model_inputs(current_model, data)
        current = {key: residual(current_model, run, live_rule) for key, run in runs.items()}
        added.append(best)
        tried = [f for f in tried if f.column != best.feature.column]

    return DiagnosisResult(
        candidates=first_ranking or [],
        added=added,
        before={key: metrics_of(r) for key, r in before.items()},
        after={key: metrics_of(r) for key, r in current.items()},
        model=current_model,
        notes=notes,
        checks_before=residual_checks(before["data"], data.time),
        checks_after=residual_checks(current["data"], data.time),
        residuals_before=before,
        residuals_after=current,
    )


def group_design(model: dict[str, Any], inputs: np.ndarray) -> np.ndarray:
    """The model's regressors: each group's inputs (and intercept) in its own columns, groups by sample index."""
    groups = serving_group_index(model["breaks"], int(model.get("n_samples", len(inputs))), model["n"], len(inputs))
    block = np.column_stack([np.ones(len(inputs)), inputs]) if model["intercept"] else inputs
    n_groups = len(model["breaks"]) + 1
    design = np.zeros((len(inputs), n_groups * block.shape[1]))
    for g in range(n_groups):
        rows = groups == g
        design[rows, g * block.shape[1] : (g + 1) * block.shape[1]] = block[rows]
    return design


def residual_checks(res: np.ndarray, time_s: np.ndarray) -> dict[str, Any]:
    rows = np.isfinite(res)
    return {"ljung_box": ljung_box(res[rows]), "drift": drift(res[rows], time_s[rows])}
