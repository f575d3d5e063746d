"""Fit a deployable AR(1) model: the time step Δτ, the fit (one-step, free-run or closed form), the model file."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.ar1.inputs import check_heat
from groupfit.ar1.modelfile import HEAT_MARGIN, AR1File
from groupfit.ar1.rule import AR1Rule
from groupfit.ar1.sampling import decimate, decimation_step  # noqa: F401 - re-exported for the fit
from groupfit.errors import InputError
from groupfit.metrics import error_metrics, prediction_accuracy
from groupfit.models.ar1 import AR1Model, closed_form_coefficients

ROD_KEYS = ("convection_W_m2K", "radius_m", "density_kg_m3", "heat_capacity_J_kgK", "expansion_1_K")
"""Keys of a rod configuration's ``[rod]`` table that the closed form needs (configs/rod_ar1.toml)."""


def closed_form_from_toml(path: str | Path) -> dict[str, float]:
    """The rod constants of a rod configuration's ``[rod]`` table (``--closed-form``)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: rod configuration not found (--closed-form)")
    try:
        rod = tomllib.loads(path.read_text(encoding="utf-8")).get("rod")
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not a TOML file ({exc})") from None
    if not isinstance(rod, dict):
        raise InputError(f"{path}: no [rod] table; the closed form needs {', '.join(ROD_KEYS)}")
    missing = [key for key in ROD_KEYS if key not in rod]
    if missing:
        raise InputError(f"{path}: [rod] lacks {', '.join(missing)}")
    try:
        return {key: float(rod[key]) for key in ROD_KEYS}
    except (TypeError, ValueError):
        raise InputError(f"{path}: [rod] values must be numbers") from None


@dataclass
class AR1Fit:
    """What ``fit --model ar1`` found: the model file, the estimator and the scores on the modelling run."""

    model: AR1File
    estimator: AR1Model
    time: np.ndarray
    error: np.ndarray
    prediction: np.ndarray
    scores: dict[str, Any]
    expectation: Any = None
    """The expected next-run error (:func:`groupfit.ar1.nextrun.expect_ar1`); None when not estimated."""

    def to_json(self) -> dict[str, Any]:
        expected = self.expectation.training() if self.expectation is not None else {}
        return {**self.model.to_dict(), **expected, "scores": self.scores}

    def summary(self) -> str:
        m, s = self.model, self.scores
        c2 = ", ".join(f"C2({level:g}) = {value:.5g} µm" for level, value in zip(m.levels, m.c2_um))
        lines = [
            f"run     {s['source']}: N = {s['n_samples']} steps of {m.sampling_period_s:g} s "
            f"(every {s['decimation']} sample(s)); heat {m.heat} -> {m.error}",
            f"model   AR(1) E(k) = C1 E(k-1) + C2(q_k): C1 = {m.c1:.6f}, {c2}; other levels by (q/level)^"
            f"{m.heat_exponent:.4g}; {m.fit.replace('_', '-')} fit",
            f"start   {m.start} (E0 = {'0' if m.start == 'zero' else 'the measured error at the start'})",
            f"free run RMS {s['rms_um']:.4g} µm, max {s['max_um']:.4g} µm, prediction accuracy "
            f"{s['accuracy_percent']:.1f} %; one-step RMS {s['one_step_rms_um']:.4g} µm",
        ]
        if "closed_form" in s:
            fitted = s["closed_form"]["least_squares"]
            c2_fit = ", ".join(f"C2({k}) = {v:.5g}" for k, v in fitted["C2"].items())
            lines.append(f"physics closed form (eq. 13-14) used; least squares gives C1 = {fitted['C1']:.6f}, {c2_fit}")
        if self.expectation is not None:
            lines.append(self.expectation.line())
        elif "expected_next_run_note" in s:
            lines.append(f"expect  no next-run estimate: {s['expected_next_run_note']}")
        return "\n".join(lines)


def fit_ar1_file(
    heat: np.ndarray,
    error: np.ndarray,
    *,
    period_s: float,
    heat_name: str,
    error_name: str,
    source: str,
    time_name: str = "time_s",
    fit_method: str = "one_step",
    start: str = "zero",
    heat_exponent: float = 5 / 3,
    rod: dict[str, float] | None = None,
) -> AR1Fit:
    """Fit C1 and C2 per heat level on a run already at the model's period and write the model file object.

    ``rod``: the rod's constants (:data:`ROD_KEYS`); then C1 and C2 come from the closed form at each
    fitted level (the heat column is a heat flux in W/m²) and the least-squares values are reported beside.
    """
    heat, error = np.asarray(heat, dtype=float), np.asarray(error, dtype=float)
    check_heat(heat, source=source, name=heat_name)
    estimator = AR1Model(heat_exponent=heat_exponent, fit_method=fit_method, start=start).fit(heat[:, None], error)
    c1, c2 = estimator.c1_, dict(estimator.c2_)
    scores: dict[str, Any] = {"source": source, "n_samples": len(error)}
    fit = fit_method
    if rod is not None:
        scores["closed_form"] = {
            "rod": rod,
            "least_squares": {"C1": c1, "C2": {f"{level:g}": value for level, value in c2.items()}},
        }
        pairs = {level: closed_form_coefficients(level, period_s=period_s, **rod) for level in c2}
        c1 = next(iter(pairs.values()))[0]
        c2 = {level: pair[1] for level, pair in pairs.items()}
        fit = "closed_form"
    if not c1 > 0.0:
        raise InputError(
            f"{source}: the {fit.replace('_', '-')} fit gives C1 = {c1:.6f}, not above 0: the step is long against "
            "the run's time constant, or the run too short for it; fit at a shorter step (--period) or on a longer run"
        )
    if not c1 < 1.0:
        raise InputError(
            f"{source}: the {fit.replace('_', '-')} fit gives C1 = {c1:.6f}, not below 1: its free run would not "
            "settle; fit at a longer step (--period) or on the free-run error (--ar1-fit free-run)"
        )
    levels = sorted(c2)
    model = AR1File(
        sampling_period_s=float(period_s),
        heat=heat_name,
        error=error_name,
        c1=float(c1),
        levels=tuple(float(v) for v in levels),
        c2_um=tuple(float(c2[v]) for v in levels),
        heat_exponent=float(heat_exponent),
        heat_max=float(max(HEAT_MARGIN * levels[-1], float(np.max(heat)))),
        start=start,
        fit=fit,
        training={"source": source, "n_samples": len(error), "time": time_name},
    ).checked()
    prediction = AR1Rule(model).replay(heat, initial_um=error[0] if start == "measured" else 0.0).prediction_um
    residual = error - prediction
    one_step = error[1:] - (c1 * error[:-1] + np.array([model.c2_for(q) for q in heat[1:]]))
    scores.update(
        error_metrics(residual),
        accuracy_percent=prediction_accuracy(error, residual),
        one_step_rms_um=float(np.sqrt(np.mean(one_step**2))),
    )
    return AR1Fit(model, estimator, np.arange(len(error)) * period_s, error, prediction, scores)


__all__ = ["AR1Fit", "ROD_KEYS", "closed_form_from_toml", "decimate", "decimation_step", "fit_ar1_file"]
