"""The model file (JSON, ``"format": "groupfit-model/1"``): write, read, rebuild."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.grouping import hard_groups, soft_groups
from groupfit.models.grouped import GroupedRegressor
from groupfit.switching import SOURCE_RANGES_KEY, rule_parameters, rule_section_problem, source_ranges

FORMAT = "groupfit-model/1"
REQUIRED = (
    "format",
    "sampling_period_s",
    "temps",
    "error",
    "intercept",
    "objective",
    "p",
    "n",
    "c",
    "breaks",
    "soft_groups",
    "coefficients",
    "objective_value",
    "switching",
)


def error_metrics(residuals: np.ndarray) -> dict[str, float]:
    """R (sum of |e|), RMS and max |e| of a residual series, in µm."""
    residuals = np.asarray(residuals, dtype=float)
    return {
        "R_um": float(np.sum(np.abs(residuals))),
        "rms_um": float(np.sqrt(np.mean(residuals**2))),
        "max_um": float(np.max(np.abs(residuals))),
    }


def default_criterion(run: Run) -> str:
    """The sensor that moves most over the run: the clearest record of the thermal state."""
    spans = np.ptp(run.temps, axis=0)
    return run.temp_names[int(np.argmax(spans))]


def model_to_dict(model: GroupedRegressor, run: Run, criterion: str | None = None) -> dict[str, Any]:
    """The model file object of a model fitted on ``run``."""
    criterion = criterion or default_criterion(run)
    if criterion not in run.temp_names:
        raise InputError(
            f"switching criterion '{criterion}' is not a model input; choose one of {', '.join(run.temp_names)}"
        )
    column = run.temp_names.index(criterion)
    coefficients = [
        ([float(b0)] if model.fit_intercept else []) + [float(v) for v in slopes]
        for b0, slopes in zip(model.intercept_, model.coef_)
    ]
    metrics = error_metrics(model.residuals_)
    metrics["sse_um2"] = float(np.sum(model.residuals_**2))
    return {
        "format": FORMAT,
        "sampling_period_s": float(run.period),
        "temps": list(run.temp_names),
        "error": run.error_name,
        "intercept": bool(model.fit_intercept),
        "objective": model.objective,
        "p": len(model.breaks_),
        "n": int(model.n),
        "c": float(model.c),
        "n_samples": int(model.n_samples_fit_),
        "breaks": list(model.breaks_),
        "hard_groups": [list(g) for g in model.hard_groups_],
        "soft_groups": [list(g) for g in model.soft_groups_],
        "coefficients": coefficients,
        "objective_value": float(model.objective_value_),
        "group_objective": [float(v) for v in model.group_objective_],
        "switching": {
            "criterion": criterion,
            "criterion_index": column,
            "criterion_series": [float(v) for v in run.temps[:, column]],
            **rule_parameters(
                {
                    "temps": list(run.temp_names),
                    "sampling_period_s": float(run.period),
                    "breaks": list(model.breaks_),
                    "n": int(model.n),
                    "intercept": bool(model.fit_intercept),
                    "coefficients": coefficients,
                },
                run.temps,
                criterion_index=column,
            ),
            SOURCE_RANGES_KEY: source_ranges(run.frame, exclude=(run.time_name, run.error_name)),
        },
        "training": {"run": run.name, **metrics},
    }


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write a file completely or not at all."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def to_json(obj: Any) -> str:
    return json.dumps(obj, indent=2, allow_nan=False) + "\n"


def save_model(model_dict: dict[str, Any], path: str | Path) -> None:
    atomic_write_text(path, to_json(model_dict))


def load_model(path: str | Path) -> dict[str, Any]:
    """Read and check a model file."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: model file not found")
    try:
        model = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not a JSON model file ({exc})") from None
    if not isinstance(model, dict) or model.get("format") != FORMAT:
        raise InputError(f"{path}: not a {FORMAT} model file (missing or different 'format')")
    missing = [key for key in REQUIRED if key not in model]
    if missing:
        raise InputError(f"{path}: model file lacks key '{missing[0]}'")
    n_groups = model["p"] + 1
    if len(model["breaks"]) != model["p"] or len(model["coefficients"]) != n_groups:
        raise InputError(f"{path}: 'breaks' and 'coefficients' do not match p = {model['p']}")
    problem = rule_section_problem(model)
    if problem:
        raise InputError(f"{path}: {problem}")
    width = len(model["temps"]) + int(model["intercept"])
    for g, row in enumerate(model["coefficients"], start=1):
        if len(row) != width or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in row):
            raise InputError(f"{path}: coefficients of group {g} must be {width} finite numbers")
    return model


def estimator_from_dict(model: dict[str, Any]) -> GroupedRegressor:
    """A fitted :class:`GroupedRegressor` with the model file's groups and coefficients."""
    estimator = GroupedRegressor(
        p=model["p"], n=model["n"], c=model["c"], objective=model["objective"], fit_intercept=model["intercept"]
    )
    coefficients = np.asarray(model["coefficients"], dtype=float)
    n_samples = int(model.get("n_samples", model["soft_groups"][-1][1]))
    estimator.breaks_ = [int(b) for b in model["breaks"]]
    estimator.n_samples_fit_ = n_samples
    estimator.hard_groups_ = hard_groups(estimator.breaks_, n_samples)
    estimator.soft_groups_ = soft_groups(estimator.breaks_, n_samples, model["n"])
    if model["intercept"]:
        estimator.intercept_, estimator.coef_ = coefficients[:, 0], coefficients[:, 1:]
    else:
        estimator.intercept_, estimator.coef_ = np.zeros(len(coefficients)), coefficients
    estimator.n_features_in_ = len(model["temps"])
    estimator.feature_names_in_ = np.asarray(model["temps"], dtype=object)
    estimator.objective_value_ = float(model["objective_value"])
    return estimator
