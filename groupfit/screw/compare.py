"""Score the ball-screw model on runs, and compare it with an MLR on the same sensors.

The seed's error metrics (Li et al. 2012, §4.3): the largest difference between
predicted and measured temperature rise at 0, 4, 8 and 12 cm from the source,
and the largest difference between predicted and measured thermal error at
the probe (16 cm). The paper's figures are 0.8 °C and 3.8 µm over its three
validation sources; :func:`paper_bounds` scales them to a run by the ratio of
its steady source rise to the paper's (C1 + C2 of the source of equal power).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from groupfit.models import MLR

from .model import BallScrewModel
from .runs import ScrewRun

PAPER_SOURCES = {50.0: ("H", 13.0, 0.1), 45.0: ("A", 12.4, 0.5), 40.0: ("B", 10.9, 0.5), 35.0: ("C", 8.9, 0.4)}
"""Seed 003's heat sources: power (W) → (name, C1, C2)."""
PAPER_H_W_M2K = 17.2
PAPER_MAX_TEMPERATURE_K = 0.8
PAPER_MAX_ERROR_UM = 3.8
PAPER_POSITIONS_M = (0.0, 0.04, 0.08, 0.12)


@dataclass
class Score:
    """The seed's metrics of one model on one run (K and µm)."""

    run: str
    model: str
    source: str | None
    max_temp_K: float | None
    max_temp_all_K: float | None
    max_temp_after_tr_K: float | None
    rms_temp_K: float | None
    max_um: float
    rms_um: float
    R_um: float
    paper: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def paper_bounds(run: ScrewRun) -> dict[str, Any]:
    """The paper's 0.8 °C and 3.8 µm scaled to the run (empty when no paper source has its power).

    Scale = the run's peak measured rise at the sensor nearest the source over
    the paper's C1 + C2 (its steady rise at 0 cm) for the source of the same power.
    """
    if "power_W" not in run.run.frame.columns:
        return {}
    power = float(np.max(run.run.frame["power_W"].to_numpy(dtype=float)))
    if power not in PAPER_SOURCES:
        return {}
    name, c1, c2 = PAPER_SOURCES[power]
    rise = float(np.max(run.rises[:, 0]))
    scale = rise / (c1 + c2)
    return {
        "paper_source": name,
        "scale": float(scale),
        "rise_sensor": run.names[0],
        "rise_sensor_m": float(run.positions[0]),
        "max_temp_K": PAPER_MAX_TEMPERATURE_K,
        "max_um": PAPER_MAX_ERROR_UM,
        "max_temp_K_scaled": float(PAPER_MAX_TEMPERATURE_K * scale),
        "max_um_scaled": float(PAPER_MAX_ERROR_UM * scale),
    }


def paper_sensors(run: ScrewRun) -> list[int]:
    """Indices of the run's sensors at the paper's validation positions (those it has; maybe none)."""
    found = [int(np.argmin(np.abs(run.positions - x))) for x in PAPER_POSITIONS_M]
    return [j for j, x in zip(found, PAPER_POSITIONS_M) if abs(run.positions[j] - x) < 1e-6]


def paper_columns(run: ScrewRun) -> list[int]:
    """Indices of the sensors at the paper's validation positions (all sensors if none match)."""
    return paper_sensors(run) or list(range(len(run.positions)))


def paper_label(run: ScrewRun) -> str:
    """Where the temperature error is taken, as printed: ``0/4/8/12 cm``, the paper's positions the run has, or
    ``all sensors`` when it has none of them."""
    found = paper_sensors(run)
    if not found:
        return "all sensors"
    return "/".join(f"{100 * run.positions[j]:g}" for j in found) + " cm"


def paper_notes(run: ScrewRun) -> list[str]:
    """What a run without some of the paper's sensors changes in its metrics: the positions the temperature error
    is taken over, and the sensor whose rise scales the paper's figures when none is at the source."""
    missing = [x for x in PAPER_POSITIONS_M if not np.any(np.abs(run.positions - x) < 1e-6)]
    if not missing:
        return []
    listed = "/".join(f"{100 * x:g}" for x in missing)
    notes = [f"{run.source}: no sensor at {listed} cm: the temperature error is over {paper_label(run)}"]
    paper = paper_bounds(run)
    if paper and paper["rise_sensor_m"] > 0:
        notes.append(
            f"{run.source}: no sensor at the source: the paper's figures are scaled by the peak rise of "
            f"{paper['rise_sensor']}, {1000 * paper['rise_sensor_m']:g} mm from it (below the source's own rise)"
        )
    return notes


def screw_prediction(model: BallScrewModel, run: ScrewRun, source: str) -> tuple[np.ndarray, np.ndarray | None]:
    """Predicted rises at the run's sensors and thermal error at its probe."""
    tau0 = model.law_input(run.rises, run.positions, run.source)
    rises = model.predict(run.time, run.positions, tau0, source)
    error = None if run.probe_x is None else model.predict_error(run.time, run.probe_x, tau0, source)
    return rises, error


def score_screw(model: BallScrewModel, run: ScrewRun, source: str) -> tuple[Score, np.ndarray, np.ndarray | None]:
    """The seed's metrics of the screw model on a run; also returns the predictions."""
    rises, error = screw_prediction(model, run, source)
    diff = np.abs(rises - run.rises)
    cols = paper_columns(run)
    late = run.time > model.identification_time_s
    metrics = _error_metrics(error, run.error)
    score = Score(
        run=run.name,
        model="screw",
        source=source,
        max_temp_K=float(diff[:, cols].max()),
        max_temp_all_K=float(diff.max()),
        max_temp_after_tr_K=float(diff[late][:, cols].max()) if late.any() else None,
        rms_temp_K=float(np.sqrt(np.mean(diff[:, cols] ** 2))),
        paper=paper_bounds(run),
        **metrics,
    )
    return score, rises, error


def score_mlr(mlr: MLR, run: ScrewRun) -> tuple[Score, np.ndarray]:
    """The MLR's metrics on a run (it predicts the error only)."""
    predicted = mlr.predict(run.run.temps)
    score = Score(
        run=run.name,
        model="mlr",
        source=None,
        max_temp_K=None,
        max_temp_all_K=None,
        max_temp_after_tr_K=None,
        rms_temp_K=None,
        paper=paper_bounds(run),
        **_error_metrics(predicted, run.error),
    )
    return score, predicted


def _error_metrics(predicted, measured) -> dict[str, float]:
    if predicted is None or measured is None:
        return {"max_um": float("nan"), "rms_um": float("nan"), "R_um": float("nan")}
    e = np.asarray(predicted) - np.asarray(measured)
    return {
        "max_um": float(np.max(np.abs(e))),
        "rms_um": float(np.sqrt(np.mean(e**2))),
        "R_um": float(np.sum(np.abs(e))),
    }


@dataclass
class ScrewComparison:
    model: BallScrewModel
    mlr: MLR
    scores: list[Score]
    predictions: dict[str, dict[str, np.ndarray]]


def compare_screw(model: BallScrewModel, identification: ScrewRun, validation: list[ScrewRun]) -> ScrewComparison:
    """Identify on ``identification`` (if ``model`` is not fitted yet), re-identify C1, C2 on each
    validation run's first t_r seconds, and score the screw model and an MLR (fitted on the
    identification run, the same sensors as inputs) on every run."""
    if not hasattr(model, "lambda_"):
        model.fit(
            identification.rises,
            identification.time,
            identification.positions,
            identification.name,
            label=identification.source,
        )
    for run in validation:
        model.fit_source(run.rises, run.time, run.positions, run.name, label=run.source)
    mlr = MLR().fit(identification.run.temps, identification.error)
    scores, predictions = [], {}
    for run in [identification, *validation]:
        screw, rises, error = score_screw(model, run, run.name)
        mlr_score, mlr_error = score_mlr(mlr, run)
        scores += [screw, mlr_score]
        predictions[run.name] = {"rises": rises, "error": error, "mlr": mlr_error}
    return ScrewComparison(model=model, mlr=mlr, scores=scores, predictions=predictions)
