"""A run's readings as the run-time rule takes them, its faults, and the samples they leave unscored.

``replay`` reads a next run as the controller does: a reading that is not a
number, or outside its valid range (``switching.temp_min_c`` … ``temp_max_c``,
a derived input's source range), is held (its last good value stands in) for
the rule's hold, then the rule is in sensor fault and commands no
compensation; those samples are not scored. ``compare`` and ``diagnose`` read
a validation run with such a reading the same way, a finite one outside the
valid range (a sensor's fault code, -999 °C) as one that is not a number: the
rule replays the run (:func:`replayed_prediction`) and the samples in sensor
fault are left out of its figures, with a note (:func:`unscored_note`). A
modelling run is never read so: a model is fitted on finite values only.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from groupfit.data import Run, numeric_column
from groupfit.model import ModelFile
from groupfit.runtime import FAULT_HELD, FAULT_SENSOR, RuleTables, SwitchingRule


def rule_readings(tables: RuleTables, run: Run) -> np.ndarray:
    """The (N, k) readings the rule takes from ``run``, in the order of ``tables.raw_names``.

    The measured inputs as the run holds them (from its table when they are
    taken relative to a reference: the rule takes each sensor's raw reading),
    then the sources of derived inputs and the reference column from its
    table; non-finite values are kept (the rule takes them as faults).
    """
    relative = getattr(run, "reference", None) is not None
    columns = []
    for name in tables.raw_names:
        if not relative and name in run.temp_names:
            columns.append(np.asarray(run.temps[:, run.temp_names.index(name)], dtype=float))
        else:
            columns.append(numeric_column(run.frame, name, run.source, allow_nonfinite=True))
    return np.column_stack(columns) if columns else np.empty((run.n_samples, 0))


def outside_valid_range(tables: RuleTables, readings: np.ndarray) -> np.ndarray:
    """Per sample and reading (the columns of :func:`rule_readings`), whether the rule takes it as a fault: not a
    number, or outside its valid range (``switching.temp_min_c`` … ``temp_max_c``, a derived input's source
    range); the rule holds such a reading, then is in sensor fault."""
    readings = np.asarray(readings, dtype=float)
    low, high = np.asarray(tables.valid_min, dtype=float), np.asarray(tables.valid_max, dtype=float)
    with np.errstate(invalid="ignore"):
        return ~((readings >= low) & (readings <= high))


def has_faulty_readings(model: ModelFile, run: Run) -> bool:
    """Whether the rule of ``model`` reads a value on ``run`` that it takes as a fault: not a number, or outside
    its valid range (:func:`outside_valid_range`)."""
    tables = RuleTables.from_model(model)
    return bool(outside_valid_range(tables, rule_readings(tables, run)).any())


RuleFaults = tuple[RuleTables, np.ndarray, np.ndarray]
"""The rule's tables, the readings it takes from a run and each sample's fault bits (:func:`rule_faults`)."""


def rule_replay(model: ModelFile, run: Run, skip: int = 0) -> tuple[np.ndarray, RuleFaults]:
    """One replay of ``run`` by the rule of ``model``: the prediction at each sample after the first ``skip``
    (a history in front), NaN where the rule is in sensor fault (it commands no compensation there); and the
    rule's tables, the readings and the fault bits on those samples.

    The prediction is the model's before the compensation's clamp, with the
    bumpless transfer after each switch and the held readings in place, as
    ``groupfit replay`` computes it without probe checks.
    """
    rule = SwitchingRule(model, period_s=run.period)
    readings = rule_readings(rule.tables, run)
    replay = rule.replay(readings).tail(skip)
    in_fault = (replay.fault & FAULT_SENSOR) != 0
    return np.where(in_fault, np.nan, replay.prediction_um), (rule.tables, readings[skip:], replay.fault)


def replayed_prediction(model: ModelFile, run: Run, skip: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The prediction of :func:`rule_replay` and each sample's fault bits (:data:`~groupfit.runtime.FAULT_HELD`,
    :data:`~groupfit.runtime.FAULT_SENSOR`)."""
    prediction, (_, _, fault) = rule_replay(model, run, skip)
    return prediction, fault


def faulty_readings(tables: RuleTables, readings: np.ndarray) -> list[dict[str, Any]]:
    """Per reading outside its valid range on some sample: its name, valid range, the samples, how many of them
    are not a number, and the values seen on the others."""
    found = []
    outside = outside_valid_range(tables, readings)
    for r, name in enumerate(tables.raw_names):
        low, high = float(tables.valid_min[r]), float(tables.valid_max[r])
        values, bad = np.asarray(readings[:, r], dtype=float), outside[:, r]
        if not bad.any():
            continue
        seen = values[bad & np.isfinite(values)]
        found.append(
            {
                "reading": str(name),
                "valid": [low, high],
                "samples": int(bad.sum()),
                "not_a_number": int(np.sum(~np.isfinite(values[bad]))),
                "seen": [float(seen.min()), float(seen.max())] if seen.size else None,
            }
        )
    return found


def reading_parts(found: list[dict[str, Any]]) -> list[str]:
    """Each faulty reading of :func:`faulty_readings` in words: ``T1 not finite (NaN or ±inf) on 20 sample(s)
    (valid 3..95)``."""
    parts = []
    for f in found:
        kinds = []
        if f["seen"]:
            beyond = f["samples"] - f["not_a_number"]
            kinds.append(f"{f['seen'][0]:.4g}..{f['seen'][1]:.4g} on {beyond} sample(s)")
        if f["not_a_number"]:
            kinds.append(f"not finite (NaN or ±inf) on {f['not_a_number']} sample(s)")
        parts.append(f"{f['reading']} {' and '.join(kinds)} (valid {f['valid'][0]:g}..{f['valid'][1]:g})")
    return parts


def fault_readings(tables: RuleTables, readings: np.ndarray, fault: np.ndarray) -> tuple[dict[str, Any], list[str]]:
    """Per reading outside its valid range on some sample: its name, valid range, the samples and the values
    seen there; and ``replay``'s note (none when the rule never held a reading)."""
    if not np.any((fault & (FAULT_SENSOR | FAULT_HELD)) != 0):
        return {}, []
    found = faulty_readings(tables, readings)
    if not found:
        return {}, []
    n = len(readings)
    whole = [f["reading"] for f in found if f["samples"] - f["not_a_number"] > n // 2]
    hint = (
        f"; {', '.join(whole)} beyond its range on most samples: logged in another unit than the modelling run "
        "(°F for °C, r/s for r/min)? convert it as that run was logged"
        if whole
        else ""
    )
    note = (
        "readings outside their valid range (held, then a sensor fault; those samples are not scored): "
        + "; ".join(reading_parts(found))
        + hint
    )
    return {"readings_out_of_range": found}, [note]


def rule_faults(model: ModelFile, run: Run, skip: int = 0) -> RuleFaults:
    """The rule's tables, the readings it takes from ``run`` and each sample's fault bits, the last two after
    the run's first ``skip`` rows (a history in front, replayed first)."""
    return rule_replay(model, run, skip)[1]


def unscored_samples(faults: RuleFaults) -> int:
    """On how many samples the rule is in sensor fault (``faults``: :func:`rule_faults`)."""
    return int(np.sum((faults[2] & FAULT_SENSOR) != 0))


def unscored_note(
    model: ModelFile, run: Run, skip: int = 0, *, others: str = "", faults: RuleFaults | None = None
) -> str | None:
    """What the rule's faults leave unscored on ``run`` (after its first ``skip`` rows), in one line naming the
    readings; None when the rule of ``model`` reads no value there that it takes as a fault (not a number, or
    outside its valid range: :func:`outside_valid_range`). ``others``: what
    the count does not cover, said after it (another model's count); ``faults``: :func:`rule_faults` of
    ``model`` on ``run``, when it was already replayed."""
    tables, readings, fault = rule_faults(model, run, skip) if faults is None else faults
    if not outside_valid_range(tables, readings).any():
        return None
    held = int(np.sum(((fault & FAULT_HELD) != 0) & ((fault & FAULT_SENSOR) == 0)))
    in_fault = int(np.sum((fault & FAULT_SENSOR) != 0))
    parts = reading_parts(faulty_readings(tables, readings))
    return (
        f"{run.name}: {'; '.join(parts)}: the run-time rule holds such a reading for up to "
        f"{tables.hold_samples} sample(s), then is in sensor fault; {in_fault} sample(s) in sensor fault are not "
        f"scored{others}, {held} on held readings are, as replay scores the run"
    )


__all__ = [
    "RuleFaults",
    "fault_readings",
    "faulty_readings",
    "has_faulty_readings",
    "outside_valid_range",
    "reading_parts",
    "replayed_prediction",
    "rule_readings",
    "rule_faults",
    "rule_replay",
    "unscored_note",
    "unscored_samples",
]
