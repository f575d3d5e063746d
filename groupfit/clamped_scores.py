"""A next run scored as the controller corrects it: a prediction beyond the compensation's clamp counts only up
to it, in ``compare``, the next-run estimate and ``diagnose`` as in ``replay`` (the clamp a model file's
switching rule holds, twice the largest prediction on the modelling run:
:func:`groupfit.runtime.rule.compensation_clamp`)."""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

LABELS = {"mlr": "MLR", "ar1": "AR(1)", "fit": "fit's model"}


def within_compensation_clamp(prediction: np.ndarray, switching: Any) -> np.ndarray:
    """What the controller corrects of ``prediction``: the compensation (the prediction's negative) held within
    the model file's switching clamp, ``switching.comp_min_um`` … ``comp_max_um``, as replay holds it; the
    prediction itself when the section sets no clamp."""
    low, high = switching.comp_min_um, switching.comp_max_um
    if low is None or high is None:
        return prediction
    return -np.clip(-prediction, low, high)


def clamped(
    predictions: Mapping[str, np.ndarray], clamps: Mapping[str, float], run: str
) -> tuple[dict[str, np.ndarray], list[str]]:
    """``predictions`` of the models with a clamp, each held within it, and a note per model the clamp binds on."""
    held, bound = dict(predictions), []
    for key, limit in clamps.items():
        if key not in predictions:
            continue
        prediction = np.asarray(predictions[key], dtype=float)
        beyond = int(np.sum(np.abs(prediction) > limit))
        if beyond:
            held[key] = np.clip(prediction, -limit, limit)
            bound.append(
                f"{LABELS.get(key, key.replace('grouped', 'grouped p = '))} (±{limit:g} µm, {beyond} sample(s))"
            )
    if not bound:
        return held, []
    return held, [
        f"{run}: the predictions of {', '.join(bound)} pass the compensation's clamp (twice the largest on the "
        "modelling run); scored as the controller corrects them, up to the clamp, as replay scores them"
    ]


__all__ = ["clamped", "within_compensation_clamp"]
