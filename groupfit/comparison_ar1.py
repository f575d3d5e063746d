"""``compare``'s physics AR(1) model: fitted as the comparison's settings say, when it is left out, its early-rise
scaling and its expected next-run error (the settings are a :class:`groupfit.comparison.ComparisonSettings`)."""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from groupfit.ar1.inputs import ar1_inputs, moves_like_measurement, next_run_inputs, temperature_on_every_row
from groupfit.ar1.nextrun import expect_ar1
from groupfit.data import Run, numeric_column
from groupfit.error_start import first_reading
from groupfit.errors import InputError
from groupfit.heldout.expect import NextRunExpectation
from groupfit.models.ar1 import AR1Model, early_rise
from groupfit.reference import column_role, refuse_as_temperature


def ar1_estimator(settings) -> AR1Model:
    """The physics AR(1) model as ``compare`` fits it, not yet fitted."""
    return AR1Model(
        structural_gain=settings.structural_gain_um_per_K if settings.structural_sensor else None,
        scaling=settings.ar1_scaling,
        heat_exponent=settings.heat_exponent,
        start=settings.ar1_start,
        fit_method=settings.ar1_fit,
    )


def fit_ar1(run: Run, settings) -> AR1Model:
    """The physics AR(1) model of a run, as ``compare`` fits it."""
    return ar1_estimator(settings).fit(ar1_inputs(run, settings.heat, settings.structural_sensor), run.error)


def expect_compared_ar1(run: Run, settings) -> NextRunExpectation | None:
    """The AR(1) model's expected next-run RMS from the modelling run alone (:mod:`groupfit.ar1.nextrun`); None
    when its unseen levels are scaled by the early rise, which a segment of the same run cannot show."""
    if settings.ar1_scaling != "heat_law":
        return None
    inputs = ar1_inputs(run, settings.heat, settings.structural_sensor)
    return expect_ar1(inputs[:, 0], run.error, prefix_predictor(inputs, run.error, settings), heat_name=settings.heat)


def prefix_predictor(inputs: np.ndarray, error: np.ndarray, settings) -> Callable[[int, int], np.ndarray]:
    """``predict(a, b)`` of the forward chaining (:func:`groupfit.ar1.nextrun.ar1_forward_chaining`): the model
    fitted on the first ``a`` samples as ``compare`` fits it, its free run over the first ``b`` from where
    ``compare`` starts one (the run's first measured error, or 0)."""
    initial = first_measured(error) if settings.ar1_start == "measured" else 0.0

    def predict(a: int, b: int) -> np.ndarray:
        return ar1_estimator(settings).fit(inputs[:a], error[:a]).predict(inputs[:b], initial_error=initial)

    return predict


def ar1_left_out_reason(modelling: Run, measured: Run, parts: Sequence[Run], heat: str | None = None) -> str | None:
    """Why the AR(1) model cannot be fitted on the modelling run(s); None when it can (a heat column that is
    missing or unreadable is refused when it is read)."""
    if measured is not modelling:
        return "the error is not measured on every row"
    if len(parts) > 1:
        return "its free run would run on from one modelling run into the next"
    if heat is not None and heat in modelling.frame.columns and not column_role(modelling, heat):
        values = pd.to_numeric(modelling.frame[heat], errors="coerce").to_numpy(dtype=float)
        moving = moves_like_measurement(values, heat) if np.isfinite(values).all() and np.all(values >= 0) else None
        if moving:
            return f"its {moving}, and the AR(1) model fits one C2 per heat level"
    return None


def first_measured(error: np.ndarray) -> float:
    """The first measured value of an error series (where an AR(1) free run starts); 0 when none is."""
    first = first_reading(np.asarray(error, dtype=float))
    return 0.0 if first is None else first


def early_rise_ratio(run: Run, modelling: Run, settings) -> float | None:
    """The run's early temperature rise over the modelling run's (``ar1_scaling = "rise"``); None otherwise."""
    if settings.ar1_scaling != "rise":
        return None
    sensor = rise_sensor(modelling, settings)
    base = early_rise(_column(modelling, sensor), modelling.period, settings.rise_window_s)
    if not (np.isfinite(base) and base != 0.0):
        raise InputError(
            f"{modelling.source}: rise sensor '{sensor}' rises by {base:g} over the first "
            f"{settings.rise_window_s:g} s, so the early-rise ratio of another run cannot be taken against it; "
            'choose a sensor that rises then, a longer [compare] rise_window_s, or ar1_scaling = "heat_law"'
        )
    return early_rise(_column(run, sensor), run.period, settings.rise_window_s) / base


def ar1_prediction(ar1: AR1Model, run: Run, modelling: Run, settings, *, next_run: bool = False) -> np.ndarray:
    """The AR(1) model's free run over ``run``, from its first measured error or from 0; on a ``next_run`` (a
    validation run) its state held where the heat reading is missed, as the AR(1) routine holds it
    (:func:`groupfit.ar1.inputs.next_run_inputs`)."""
    rise_ratio = early_rise_ratio(run, modelling, settings)
    initial = first_measured(run.error) if settings.ar1_start == "measured" else 0.0
    if not next_run:
        inputs = ar1_inputs(run, settings.heat, settings.structural_sensor)
        return ar1.predict(inputs, initial_error=initial, rise_ratio=rise_ratio)
    inputs, held = next_run_inputs(run, settings.heat, settings.structural_sensor)
    return ar1.predict(inputs, initial_error=initial, rise_ratio=rise_ratio, held=held)


def held_heat_notes(run: Run, settings, prediction: np.ndarray) -> list[str]:
    """The note on a validation run whose heat reading is missed on some rows (empty, NaN or ±inf): the AR(1)
    routine holds its state there, and of those rows the ones with a measured error and a ``prediction`` (the
    AR(1) row's, as scored) are scored on the held state; none when the heat is read on every row."""
    heat = numeric_column(run.frame, settings.heat, str(run.source), allow_nonfinite=True)
    missed = ~np.isfinite(heat)
    if not missed.any():
        return []
    scored = int(np.sum(missed & np.isfinite(run.error - prediction)))
    return [
        f"{run.name}: AR(1) heat column '{settings.heat}': {int(missed.sum())} sample(s) without a reading (empty, "
        "NaN or ±inf): the AR(1) routine holds its state on such a reading (no step), as replay of an AR(1) model "
        f"file does; {scored} of those sample(s) are scored on the held state"
        + ("" if scored == missed.sum() else " (the others have no measured error)")
    ]


def rise_sensor(modelling: Run, settings) -> str:
    """The temperature whose early rise scales C2 (``[compare] rise_sensor``, else the first input), refused when
    it is the run's time, error or a speed."""
    sensor = settings.rise_sensor or modelling.temp_names[0]
    refuse_as_temperature(modelling, sensor, "rise sensor", "name a temperature with [compare] rise_sensor")
    if sensor == settings.heat:
        raise InputError(
            f"{modelling.source}: rise sensor '{sensor}' is the AR(1) model's heat column, not a temperature; name a "
            "temperature with [compare] rise_sensor"
        )
    return sensor


def rise_notes(modelling: Run, settings) -> list[str]:
    """The note that names the rise sensor when ``[compare] rise_sensor`` does not."""
    if settings.heat is None or settings.ar1_scaling != "rise" or settings.rise_sensor:
        return []
    return [
        f"the AR(1) model scales unseen heat levels by the early rise of {rise_sensor(modelling, settings)}, the "
        "first input; [compare] rise_sensor names another"
    ]


def _column(run: Run, name: str) -> np.ndarray:
    if name not in run.frame.columns:
        raise InputError(f"{run.source}: rise sensor '{name}' not found; set [compare] rise_sensor")
    return temperature_on_every_row(run, name)


__all__ = [
    "ar1_estimator",
    "ar1_left_out_reason",
    "early_rise_ratio",
    "expect_compared_ar1",
    "first_measured",
    "fit_ar1",
    "held_heat_notes",
    "prefix_predictor",
    "rise_notes",
    "rise_sensor",
]
