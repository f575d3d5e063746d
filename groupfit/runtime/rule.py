"""The run-time rule's parameters, derived from a model and its modelling run.

:func:`rule_parameters` fills a model file's ``switching`` section (windows,
thresholds, directions, margin, hold, valid ranges, clamp, rate limit);
:func:`source_ranges` the valid range of every other column, for derived
inputs added later. The rule itself is described in :mod:`groupfit.runtime`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from groupfit.errors import InputError
from groupfit.grouping import serving_group_index
from groupfit.model import RULE_KEYS, ModelFile, Switching
from groupfit.switching_checks import RULE_LIMIT, switch_direction

RULE_FORMAT = "groupfit-switch/1"
COUNT_MAX = 2_000_000_000
"""The sample count saturates here (fits a 32-bit signed integer: a PLC DINT)."""

FAULT_NONE = 0
FAULT_HELD = 1
"""Fault bit: a reading was invalid and its last good value was used; the output is valid."""
FAULT_SENSOR = 2
"""Fault bit: a reading has been invalid for more than K samples (or was never valid): safe output."""
FAULT_PERIOD = 4
"""Fault bit used by the Structured Text block when its task period differs from the model's."""
FAULT_POSITION = 8
"""Flag of a position model: the axis position lay outside the modelled travel and was clamped to it (output valid)."""

RETURN_SENSOR_FAULT = -1
"""What the exported step routines return instead of the group under a sensor fault."""
RETURN_PERIOD_FAULT = -2
"""What the exported period checks return when the sampling period differs from the model's."""

SWITCH_NONE, SWITCH_CRITERION, SWITCH_FORCED = 0, 1, 2
PERIOD_TOLERANCE = 0.01
"""Largest relative difference between the live and the model's sampling period."""


@dataclass(frozen=True)
class RuleSettings:
    """How :func:`rule_parameters` derives the rule from the modelling run."""

    noise_c: float = 0.05
    """Smallest sensor noise (standard deviation, °C) the criterion test must tolerate; the noise estimated
    from the modelling run's criterion is used when it is larger."""
    margin_sigmas: float = 3.0
    """The criterion margin in noise standard deviations."""
    hold_s: float = 300.0
    """How long (s) a sensor's last good value may stand in for invalid readings; K = ``floor(hold_s /
    period)``, at least 1."""
    range_margin_c: float = 15.0
    """A reading is valid within the modelling run's range of that sensor widened by this much (°C) on each
    side, rounded outward to whole °C."""
    clamp_factor: float = 2.0
    """The compensation is clamped to ``±max(clamp_floor_um, clamp_factor · max|ŷ|)`` over the modelling
    run, rounded up to 1 µm."""
    clamp_floor_um: float = 10.0
    rate_factor: float = 2.0
    """Rate limit per sample: ``max(rate_floor_um, rate_factor · max|Δŷ|)`` over consecutive samples served
    by the same group in the modelling run, rounded up to 0.1 µm. Jumps at group switches are spread."""
    rate_floor_um: float = 0.5


LEGACY_TEMP_RANGE_C = (-50.0, 200.0)
"""Valid range for sensors whose modelling range is unknown (model files without the rule keys)."""
LEGACY_COMP_LIMIT_UM = 1000.0
"""Clamp and rate limit used when the modelling run's predictions are unknown."""
LEGACY_SOURCE_RANGE = (-1.0e9, 1.0e9)
"""Valid range of a source column whose modelling range the model file does not hold (any sane number)."""

DERIVATIVE_SCALE_S = 3600.0
"""A derivative is per hour: ``(x[k] − x[k−1])·3600/Δt``."""


def switch_windows(breaks: Sequence[int], n: int) -> list[list[int]]:
    """Window of every switch: 1-based ``[first, last]`` samples.

    Window g (between groups g and g+1, hard break ``b``) is the overlap of
    the two soft groups, ``b − n + 1 … b``: its first sample is the first one
    the offline model serves with group g+1. With ``n = 0`` the window is the
    single sample ``b + 1``.
    """
    windows = []
    for b in breaks:
        first = int(b) - int(n) + 1
        windows.append([first, max(int(b), first)])
    return windows


def estimate_noise(series: np.ndarray) -> float:
    """Robust noise level (°C) of a smooth series, from its second differences.

    The median absolute deviation of the second differences, scaled to a
    standard deviation for white noise (``√6`` σ per second difference).
    """
    series = np.asarray(series, dtype=float)
    series = series[np.isfinite(series)]
    if len(series) < 3:
        return 0.0
    second = np.diff(series, 2)
    mad = float(np.median(np.abs(second - np.median(second))))
    return 1.4826 * mad / math.sqrt(6.0)


def rule_parameters(
    model: ModelFile | Mapping[str, Any],
    modelling_readings: np.ndarray | None = None,
    *,
    criterion_index: int | None = None,
    settings: RuleSettings = RuleSettings(),
    valid_readings: np.ndarray | None = None,
) -> dict[str, Any]:
    """Derive the switching rule's parameters from the modelling run.

    Parameters
    ----------
    model : ModelFile or model file object
        The model (``switching.criterion_index`` and
        ``switching.criterion_series`` are used when ``criterion_index`` or
        ``modelling_readings`` are not given).
    modelling_readings : ndarray, shape (N, k), optional
        The modelling run's inputs, in the model's input order. Without
        them (an older model file) only the criterion series is known: valid
        ranges of the other sensors, the clamp and the rate limit fall back to
        wide defaults (:data:`LEGACY_TEMP_RANGE_C`, :data:`LEGACY_COMP_LIMIT_UM`).
    criterion_index : int, optional
        0-based column of the criterion sensor.
    settings : RuleSettings
    valid_readings : ndarray, shape (N, k), optional
        The readings the valid ranges are taken from, when they differ from
        the model's inputs: a model with a reference temperature takes rises
        over the reference as inputs, but the rule checks each sensor's raw
        reading (default: ``modelling_readings``).

    Returns
    -------
    dict
        The keys of :data:`RULE_KEYS`: ``windows`` (1-based ``[first, last]``
        per break), ``thresholds_c`` (the modelling run's criterion at each
        window's first sample), ``directions`` (+1 rising, −1 falling, 0 index
        only), ``noise_c`` and ``margin_c``, ``hold_samples`` (K),
        ``temp_min_c`` / ``temp_max_c`` per sensor, ``comp_min_um`` /
        ``comp_max_um``, ``rate_limit_um`` (per sample) and
        ``period_tolerance``.
    """
    if not isinstance(model, ModelFile):  # the rule keys are what this derives: earlier values do not count
        section = {k: v for k, v in model.get("switching", {}).items() if k not in RULE_KEYS}
        model = {**model, "switching": section}
    model = ModelFile.coerce(model)
    section = model.switching
    if criterion_index is None:
        criterion_index = int(section.criterion_index)
    if modelling_readings is not None:
        modelling_readings = np.asarray(modelling_readings, dtype=float)
        criterion = modelling_readings[:, criterion_index]
    else:
        criterion = np.asarray(section.criterion_series, dtype=float)
    n_inputs = len(model.temps)
    windows = switch_windows(model.breaks, int(model.n))
    noise = max(settings.noise_c, estimate_noise(criterion))
    margin = settings.margin_sigmas * noise
    thresholds, directions = [], []
    for first, last in windows:
        thresholds.append(float(criterion[first - 1]))
        before = criterion[max(first - 2, 0)]
        change = float(criterion[min(last, len(criterion)) - 1] - before)
        directions.append(switch_direction(change, margin))

    period = float(model.sampling_period_s)
    hold = max(1, int(math.floor(settings.hold_s / period + 1e-9)))

    if modelling_readings is not None:
        ranged = modelling_readings if valid_readings is None else np.asarray(valid_readings, dtype=float)
        low = np.floor(ranged.min(axis=0) - settings.range_margin_c)
        high = np.ceil(ranged.max(axis=0) + settings.range_margin_c)
        group = serving_group_index(model.breaks, len(modelling_readings), int(model.n))
        prediction = model.predict(modelling_readings, group)
        clamp = compensation_clamp(prediction, settings)
        same_group = group[1:] == group[:-1]
        steps = np.abs(np.diff(prediction))[same_group]
        largest_step = float(steps.max()) if steps.size else 0.0
        rate = max(settings.rate_floor_um, math.ceil(10.0 * settings.rate_factor * largest_step) / 10.0)
    else:
        low = np.full(n_inputs, LEGACY_TEMP_RANGE_C[0])
        high = np.full(n_inputs, LEGACY_TEMP_RANGE_C[1])
        low[criterion_index] = math.floor(float(np.min(criterion)) - settings.range_margin_c)
        high[criterion_index] = math.ceil(float(np.max(criterion)) + settings.range_margin_c)
        clamp = rate = LEGACY_COMP_LIMIT_UM

    return {
        "rule": RULE_FORMAT,
        "windows": windows,
        "thresholds_c": thresholds,
        "directions": directions,
        "noise_c": float(noise),
        "margin_c": float(margin),
        "hold_samples": int(hold),
        "temp_min_c": [float(v) for v in low],
        "temp_max_c": [float(v) for v in high],
        "comp_min_um": -float(clamp),
        "comp_max_um": float(clamp),
        "rate_limit_um": float(rate),
        "period_tolerance": PERIOD_TOLERANCE,
        "blend_samples": int(model.n),
    }


def compensation_clamp(prediction, settings: RuleSettings = RuleSettings()) -> float:
    """The clamp (µm) of the compensation, from the modelling run's predictions (:attr:`RuleSettings.clamp_factor`)."""
    return max(settings.clamp_floor_um, math.ceil(settings.clamp_factor * float(np.max(np.abs(prediction)))))


def source_valid_range(values) -> tuple[float, float] | None:
    """Valid range of a column that may feed a derived input, from its modelling values.

    Temperatures that are model inputs get ``±range_margin_c`` (°C); any
    other column (an ambient temperature, a spindle speed in r/min, an on/off
    signal) is judged on its own scale:

    * a column whose modelling values are all 0 or 1 is an on/off signal:
      valid exactly within ``[0, 1]``;
    * any other column: its modelling range ``[lo, hi]`` widened on each
      side by the larger of its span ``hi − lo`` and half its largest
      magnitude ``max(|lo|, |hi|)/2`` (at least 1 unit), not below 0 when the
      modelling run never went below 0, rounded outward to whole units (and
      to a number exact in single precision). A speed run at 0 and 2000
      r/min is valid within 0…4000 r/min; an ambient temperature of
      19.5…23.8 °C within 7…36 °C.

    Returns None for a column without a finite value.
    """
    array = np.asarray(values, dtype=float)
    array = array[np.isfinite(array)]
    if array.size == 0:
        return None
    low, high = float(array.min()), float(array.max())
    if np.all((array == 0.0) | (array == 1.0)):
        return 0.0, 1.0
    largest = float(np.finfo(np.float32).max)
    with np.errstate(over="ignore", invalid="ignore"):
        margin = max(high - low, max(abs(low), abs(high)) / 2.0, 1.0)
        bottom = float(np.floor(low - margin))
        top = float(np.ceil(high + margin))
    if low >= 0.0:
        bottom = max(bottom, 0.0)
    return _single_outward(min(max(bottom, -largest), largest), min(max(top, -largest), largest))


def _single_outward(low: float, high: float) -> tuple[float, float]:
    """``[low, high]`` widened to the nearest numbers that single precision holds exactly."""
    low32, high32 = np.float32(low), np.float32(high)
    if float(low32) > low:
        low32 = np.nextafter(low32, np.float32(-np.inf))
    if float(high32) < high:
        high32 = np.nextafter(high32, np.float32(np.inf))
    return float(low32), float(high32)


def source_ranges(frame, exclude: Sequence[str | None] = ()) -> dict[str, list[float]]:
    """Valid range (:func:`source_valid_range`) of every numeric column of a modelling run (not a date-time,
    nor one beyond the rule's limit, such as a Unix time stamp, that no input is derived from).

    Stored in a model file's switching section (:data:`SOURCE_RANGES_KEY`):
    a derived input added later (``groupfit diagnose``) may take any of these
    columns as its source, and the rule needs its valid range.
    """
    import pandas as pd

    ranges = {}
    for column in frame.columns:
        cells = frame[column]
        if column in exclude or pd.api.types.is_datetime64_any_dtype(cells) or pd.api.types.is_timedelta64_dtype(cells):
            continue
        valid = source_valid_range(pd.to_numeric(cells, errors="coerce").to_numpy(dtype=float))
        if valid is not None and max(abs(valid[0]), abs(valid[1])) <= RULE_LIMIT:
            ranges[str(column)] = [valid[0], valid[1]]
    return ranges


def complete_rule_section(model: ModelFile | Mapping[str, Any]) -> Switching:
    """The model's switching section with every rule parameter (derived from the criterion series when absent)."""
    model = ModelFile.coerce(model)
    section = model.switching
    if section.criterion_index is None:
        raise InputError("the model's switching section names no criterion_index; fit the model again")
    if section.criterion is None:
        section = dataclasses.replace(section, criterion=model.temps[section.criterion_index])
    if section.has_rule:
        return section
    if section.criterion_series is None:
        raise InputError(
            "the model's switching section has neither the rule parameters nor the criterion_series "
            "to derive them from; fit the model again"
        )
    derived = rule_parameters(model, None, criterion_index=int(section.criterion_index))
    derived.pop("blend_samples")  # a file without it switches hard, as when it was written
    present = {key: getattr(section, key) for key in RULE_KEYS if getattr(section, key) is not None}
    return section.with_rule({**derived, **present})
