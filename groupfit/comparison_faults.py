"""``compare`` on a validation run with a reading the run-time rule takes as a fault: the models replayed as
``replay`` replays them.

A validation run is read as ``replay`` reads a next run (:mod:`groupfit.rule_faults`): a reading that is
not a number, or a finite one outside its valid range (a sensor's fault code, -999 °C), is held for the
run-time rule's hold, then the rule is in sensor fault and those samples are not scored. On such a run the
MLR, the grouped models and fit's model are each replayed by the rule of its model file (the MLR's as
``fit --p 0`` writes it); the AR(1) model, which has no such rule, is left unscored on the samples where any
of them is in fault, so that it is scored on the samples the others are. A note says how many samples were
not scored, and why. The prediction band of a replayed model is left out where its rule held or faulted a
reading (it is the band of the reading as logged).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from groupfit.clamped_scores import LABELS
from groupfit.data import Run
from groupfit.model import ModelFile
from groupfit.rule_faults import has_faulty_readings, rule_replay, unscored_note
from groupfit.runtime import FAULT_HELD, FAULT_SENSOR


def model_label(key: str) -> str:
    """A compared model by name: ``MLR``, ``grouped p = 2``, ``fit's model``."""
    return LABELS.get(key, key.replace("grouped", "grouped p = "))


def replayed_on_faults(
    predictions: Mapping[str, np.ndarray],
    model_files: Mapping[str, ModelFile],
    whole: Run,
    skip: int = 0,
    bands: Mapping[str, tuple | None] | None = None,
) -> tuple[dict[str, np.ndarray], list[str], dict[str, tuple | None]]:
    """The ``predictions`` of a validation run, each model of ``model_files`` whose rule reads a value it takes
    as a fault on it (not a number, or outside its valid range) replayed by that rule (NaN in sensor fault), a
    model without a model file (the AR(1)) NaN where any replayed one is in fault; a note on what was not scored
    (none when no rule reads such a value on the run itself); and the prediction ``bands``, a replayed model's
    left out (NaN) where its rule held or faulted a reading.

    ``whole``: the run with its history in front, of which the first ``skip``
    rows are the history.
    """
    replayed, in_fault, counts, faults = dict(predictions), np.zeros(whole.n_samples - skip, dtype=bool), {}, {}
    bands = dict(bands or {})
    for key, model in model_files.items():
        if key in predictions and has_faulty_readings(model, whole):
            replayed[key], faults[key] = rule_replay(model, whole, skip)
            counts[key] = (faults[key][2] & FAULT_SENSOR) != 0
            in_fault |= counts[key]
            bands[key] = without_faults(bands.get(key), faults[key][2])
    if not counts:
        return replayed, [], bands
    unscored = [key for key in predictions if key not in model_files]
    for key in unscored:
        replayed[key] = np.where(in_fault, np.nan, predictions[key])
    first = next(iter(counts))
    differing = [
        f"{model_label(key)}: {int(mask.sum())}" for key, mask in counts.items() if (mask != counts[first]).any()
    ]
    others = f" by {model_label(first)} ({', '.join(differing)})" if differing else ""
    note = unscored_note(model_files[first], whole, skip, others=others, faults=faults[first])
    if note is None:  # the faulty readings lie in the history in front
        return replayed, [], bands
    if unscored and in_fault.any():
        note += (
            f"; {' and '.join(model_label(key) for key in unscored)} left unscored on the samples a rule is in fault"
        )
    return replayed, [note], bands


def without_faults(band: tuple | None, fault: np.ndarray) -> tuple | None:
    """A (lower, upper) prediction band left out (NaN) on the samples whose ``fault`` bits say the rule held a
    reading or was in sensor fault; None stays None."""
    if band is None:
        return None
    off = (np.asarray(fault) & (FAULT_HELD | FAULT_SENSOR)) != 0
    return tuple(np.where(off, np.nan, np.asarray(end, dtype=float)) for end in band)


__all__ = ["model_label", "replayed_on_faults", "without_faults"]
