"""Run-time coefficient switching: the reference implementation.

A grouped model holds one coefficient vector per soft group. While a machine
runs, something must pick the vector that serves the current sample. The
paper (docs/methods.md §1, eq. 16) outlines the rule: a sample count that advances
at the modelling run's sampling period, and a criterion temperature compared
with the modelling run's criterion at the same sample index. This module makes
that rule exact; the exported C, Structured Text and JSON routines
(:mod:`groupfit.export`) perform the same operations in the same order, so
their decisions are identical sample for sample.

The rule, per sample (``docs/switching.md`` has the full account)
-----------------------------------------------------------------
State: current group ``g`` (1-based, starts at 1), sample count ``i``, the last
good reading of every sensor and how many samples ago it was good, the state
of every derived input (low-pass output, previous value, delay line), and the
compensation value last handed to the controller.

The rule's *readings* (its raw inputs) are the model's measured inputs (the
``temps`` that are not derived), then the source columns of its derived
inputs (``derived_inputs``, :mod:`groupfit.features`) that are not among
them, in order of first appearance in ``temps``.

1. ``i ← i + 1`` (saturating at :data:`COUNT_MAX`).
2. Every reading is *valid* when ``temp_min_c ≤ x ≤ temp_max_c`` (NaN and
   ±inf never are). A valid reading replaces the sensor's last good value; an
   invalid one keeps it and counts a bad sample. Up to ``hold_samples`` (K)
   bad samples in a row are *held* (fault bit 1, the output stays valid);
   more, or a bad reading before any good one, is a *sensor fault*
   (fault bit 2).
   Every derived input is then computed from the last good value of its
   source, with its own state, exactly as :class:`groupfit.features.Feature`
   defines it: ``identity``; ``lowpass`` ``y = b·x + a·y`` (``a = e^{−Δt/τ}``,
   ``b = 1 − a``, the state starts at the source's first good reading);
   ``derivative`` ``(x − x_prev)·3600/Δt`` (0 at the first good reading);
   ``delay`` ``x`` of ``d`` samples before (the first good reading before
   that). A held source feeds its transform as if it were the reading.
3. Switching from group g to g+1 (only while g < G) is possible only inside
   window g, ``first ≤ i ≤ last``: the ``n`` samples that soft groups g and
   g+1 share (the window's first sample is the one from which the offline
   model serves g+1). At ``i ≥ last`` the switch is *forced*; before that it
   happens when the criterion has reached the modelling run's criterion value
   at the window's first sample, ``threshold``, in the direction the
   modelling run was moving: ``criterion − threshold ≥ −margin`` (rising) or
   ``≤ margin`` (falling). A window whose criterion moved less than the
   margin has direction 0 and switches at its first sample, as does any
   window while the criterion sensor is in sensor fault. One group per
   sample at most, never backwards.
4. Prediction ``ŷ = c₀ + Σ c_m·x_m`` of the current group with the model's
   inputs (held readings and derived inputs), accumulated in input order;
   under a sensor fault ``ŷ = 0`` (the safe output: no compensation).
5. Compensation: target ``−ŷ`` (0 under a sensor fault) clamped to
   ``[comp_min_um, comp_max_um]``, then moved from its previous value by at
   most ``rate_limit_um`` per sample. It starts at 0.

Everything is computed in double precision, or, with ``precision="single"``,
in IEEE single precision operation for operation as the C build with
``GF_USE_FLOAT`` (and a PLC's REAL) computes it, so that the results agree bit
for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from groupfit.errors import InputError
from groupfit.features import Feature
from groupfit.grouping import serving_group_index

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

RETURN_SENSOR_FAULT = -1
"""What the exported step routines return instead of the group under a sensor fault."""
RETURN_PERIOD_FAULT = -2
"""What the exported period checks return when the sampling period differs from the model's."""

SWITCH_NONE, SWITCH_CRITERION, SWITCH_FORCED = 0, 1, 2
PERIOD_TOLERANCE = 0.01
"""Largest relative difference between the live and the model's sampling period."""

RULE_KEYS = (
    "rule",
    "windows",
    "thresholds_c",
    "directions",
    "noise_c",
    "margin_c",
    "hold_samples",
    "temp_min_c",
    "temp_max_c",
    "comp_min_um",
    "comp_max_um",
    "rate_limit_um",
    "period_tolerance",
)
"""Keys :func:`rule_parameters` adds to a model file's ``switching`` section."""


@dataclass(frozen=True)
class RuleSettings:
    """How :func:`rule_parameters` derives the rule from the modelling run.

    Attributes
    ----------
    noise_c : float
        Smallest sensor noise (standard deviation, °C) the criterion test
        must tolerate; the noise estimated from the modelling run's criterion
        is used when it is larger.
    margin_sigmas : float
        The criterion margin in noise standard deviations.
    hold_s : float
        How long (s) a sensor's last good value may stand in for invalid
        readings; K = ``floor(hold_s / period)``, at least 1.
    range_margin_c : float
        A reading is valid within the modelling run's range of that sensor
        widened by this much (°C) on each side, rounded outward to whole °C.
    clamp_factor, clamp_floor_um : float
        The compensation is clamped to ``±max(clamp_floor_um,
        clamp_factor · max|ŷ|)`` over the modelling run, rounded up to 1 µm.
    rate_factor, rate_floor_um : float
        Rate limit per sample: ``max(rate_floor_um, rate_factor · max|Δŷ|)``
        over consecutive samples served by the same group in the modelling
        run, rounded up to 0.1 µm. Jumps at group switches are spread.
    """

    noise_c: float = 0.05
    margin_sigmas: float = 3.0
    hold_s: float = 300.0
    range_margin_c: float = 15.0
    clamp_factor: float = 2.0
    clamp_floor_um: float = 10.0
    rate_factor: float = 2.0
    rate_floor_um: float = 0.5


LEGACY_TEMP_RANGE_C = (-50.0, 200.0)
"""Valid range for sensors whose modelling range is unknown (model files without the rule keys)."""
LEGACY_COMP_LIMIT_UM = 1000.0
"""Clamp and rate limit used when the modelling run's predictions are unknown."""
LEGACY_SOURCE_RANGE = (-1.0e9, 1.0e9)
"""Valid range of a source column whose modelling range the model file does not hold (any sane number)."""

SOURCE_RANGES_KEY = "source_ranges"
"""Key of the switching section holding the valid range of every other column of the modelling run."""
MAX_DELAY_SAMPLES = 32767
"""Longest delay line of a derived input (its position is a PLC INT)."""
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


def offline_predictions(model: dict[str, Any], temps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Prediction of every modelling sample by its serving group, and that group (0-based)."""
    temps = np.asarray(temps, dtype=float)
    coefficients = coefficient_matrix(model)
    n_samples = len(temps)
    group = serving_group_index(model["breaks"], n_samples, int(model["n"]))
    prediction = coefficients[group, 0] + np.einsum("ij,ij->i", temps, coefficients[group, 1:])
    return prediction, group


def coefficient_matrix(model: dict[str, Any]) -> np.ndarray:
    """Coefficients as a (G, M+1) array, constant first (0 when the model has none)."""
    coefficients = np.asarray(model["coefficients"], dtype=float)
    if not model["intercept"]:
        coefficients = np.column_stack([np.zeros(len(coefficients)), coefficients])
    return coefficients


def rule_parameters(
    model: dict[str, Any],
    modelling_temps: np.ndarray | None = None,
    *,
    criterion_index: int | None = None,
    settings: RuleSettings = RuleSettings(),
) -> dict[str, Any]:
    """Derive the switching rule's parameters from the modelling run.

    Parameters
    ----------
    model : dict
        A model file object (at least ``breaks``, ``n``, ``coefficients``,
        ``intercept``, ``sampling_period_s``; ``switching.criterion_index``
        and ``switching.criterion_series`` when ``criterion_index`` or
        ``modelling_temps`` are not given).
    modelling_temps : ndarray, shape (N, k), optional
        The modelling run's temperatures, in the model's input order. Without
        them (an older model file) only the criterion series is known: valid
        ranges of the other sensors, the clamp and the rate limit fall back to
        wide defaults (:data:`LEGACY_TEMP_RANGE_C`, :data:`LEGACY_COMP_LIMIT_UM`).
    criterion_index : int, optional
        0-based column of the criterion sensor.
    settings : RuleSettings

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
    section = model.get("switching", {})
    if criterion_index is None:
        criterion_index = int(section["criterion_index"])
    if modelling_temps is not None:
        modelling_temps = np.asarray(modelling_temps, dtype=float)
        criterion = modelling_temps[:, criterion_index]
    else:
        criterion = np.asarray(section["criterion_series"], dtype=float)
    n_temps = len(model["temps"]) if "temps" in model else (modelling_temps.shape[1])
    windows = switch_windows(model["breaks"], int(model["n"]))

    noise = max(settings.noise_c, estimate_noise(criterion))
    margin = settings.margin_sigmas * noise
    thresholds, directions = [], []
    for first, last in windows:
        thresholds.append(float(criterion[first - 1]))
        before = criterion[max(first - 2, 0)]
        change = float(criterion[min(last, len(criterion)) - 1] - before)
        directions.append(0 if abs(change) <= margin else (1 if change > 0 else -1))

    period = float(model["sampling_period_s"])
    hold = max(1, int(math.floor(settings.hold_s / period + 1e-9)))

    if modelling_temps is not None:
        low = np.floor(modelling_temps.min(axis=0) - settings.range_margin_c)
        high = np.ceil(modelling_temps.max(axis=0) + settings.range_margin_c)
        prediction, group = offline_predictions(model, modelling_temps)
        clamp = max(settings.clamp_floor_um, math.ceil(settings.clamp_factor * float(np.max(np.abs(prediction)))))
        same_group = group[1:] == group[:-1]
        steps = np.abs(np.diff(prediction))[same_group]
        largest_step = float(steps.max()) if steps.size else 0.0
        rate = max(settings.rate_floor_um, math.ceil(10.0 * settings.rate_factor * largest_step) / 10.0)
    else:
        low = np.full(n_temps, LEGACY_TEMP_RANGE_C[0])
        high = np.full(n_temps, LEGACY_TEMP_RANGE_C[1])
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
    }


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
    """Valid range (:func:`source_valid_range`) of every numeric column of a modelling run.

    Stored in a model file's switching section (:data:`SOURCE_RANGES_KEY`):
    a derived input added later (``groupfit diagnose``) may take any of these
    columns as its source, and the rule needs its valid range.
    """
    import pandas as pd

    ranges = {}
    for column in frame.columns:
        if column in exclude:
            continue
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
        valid = source_valid_range(values)
        if valid is not None:
            ranges[str(column)] = [valid[0], valid[1]]
    return ranges


def derived_input_features(model: dict[str, Any]) -> dict[str, Feature]:
    """The derived inputs the model uses, by input name (as :mod:`groupfit.diagnose.residual` finds them).

    Raises InputError for an entry that does not describe a transform of
    :mod:`groupfit.features`, whose ``name`` does not match its transform, or
    whose delay is longer than :data:`MAX_DELAY_SAMPLES`.
    """
    entries = model.get("derived_inputs", [])
    if not isinstance(entries, list):
        raise InputError("'derived_inputs' must be a list")
    features = {}
    for k, entry in enumerate(entries):
        where = f"derived_inputs[{k}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("column"), str):
            raise InputError(f"{where} must be an object with a 'column' name")
        tau = entry.get("tau_s")
        if tau is not None and not _is_number(tau):
            raise InputError(f"{where}: tau_s must be a finite number")
        delay = entry.get("delay_samples", 0)
        if not isinstance(delay, int) or isinstance(delay, bool):
            raise InputError(f"{where}: delay_samples must be a whole number")
        try:
            feature = Feature.from_dict(entry)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
        if "name" in entry and entry["name"] != feature.name:
            raise InputError(f"{where}: name '{entry['name']}' does not match its transform ('{feature.name}')")
        if feature.transform == "delay" and feature.delay_samples > MAX_DELAY_SAMPLES:
            raise InputError(f"{where}: delay of {feature.delay_samples} samples; at most {MAX_DELAY_SAMPLES}")
        features[feature.name] = feature
    return {name: features[name] for name in model.get("temps", []) if name in features}


def rule_section_problem(model: dict[str, Any]) -> str | None:
    """What is wrong with a model file's switching section, or None.

    Only keys that are present are checked, so older files without the rule
    keys stay loadable (the rule then derives them from ``criterion_series``).
    """
    section = model.get("switching")
    if not isinstance(section, dict):
        return "'switching' must be an object"
    n_temps = len(model.get("temps", []))
    n_breaks = len(model.get("breaks", []))
    index = section.get("criterion_index", 0)
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < n_temps:
        return f"switching.criterion_index must be a column number 0…{n_temps - 1}"
    series = section.get("criterion_series", [0.0])
    if not isinstance(series, list) or not series or not all(_is_number(v) for v in series):
        return "switching.criterion_series must be a list of finite numbers"
    per_break = {"windows": n_breaks, "thresholds_c": n_breaks, "directions": n_breaks}
    per_sensor = {"temp_min_c": n_temps, "temp_max_c": n_temps}
    for key, length in {**per_break, **per_sensor}.items():
        if key in section and (not isinstance(section[key], list) or len(section[key]) != length):
            return f"switching.{key} must be a list of {length} entries"
    for key in ("thresholds_c", "temp_min_c", "temp_max_c"):
        if key in section and not all(_is_number(v) for v in section[key]):
            return f"switching.{key} must hold finite numbers"
    if "directions" in section and not all(v in (-1, 0, 1) for v in section["directions"]):
        return "switching.directions must hold -1, 0 or 1"
    if "windows" in section:
        for w in section["windows"]:
            if not (isinstance(w, list) and len(w) == 2 and all(isinstance(v, int) for v in w) and 1 <= w[0] <= w[1]):
                return "switching.windows must be [first, last] sample pairs with 1 ≤ first ≤ last"
    for key in ("noise_c", "margin_c", "comp_min_um", "comp_max_um", "rate_limit_um", "period_tolerance"):
        if key in section and not _is_number(section[key]):
            return f"switching.{key} must be a finite number"
    if "margin_c" in section and section["margin_c"] < 0:
        return "switching.margin_c must not be negative"
    if "rate_limit_um" in section and section["rate_limit_um"] <= 0:
        return "switching.rate_limit_um must be positive"
    if "comp_min_um" in section and "comp_max_um" in section and section["comp_min_um"] > section["comp_max_um"]:
        return "switching.comp_min_um must not exceed comp_max_um"
    if "hold_samples" in section and (not isinstance(section["hold_samples"], int) or section["hold_samples"] < 0):
        return "switching.hold_samples must be a whole number ≥ 0"
    if "temp_min_c" in section and "temp_max_c" in section:
        if any(lo > hi for lo, hi in zip(section["temp_min_c"], section["temp_max_c"])):
            return "switching.temp_min_c must not exceed temp_max_c"
    if SOURCE_RANGES_KEY in section:
        ranges = section[SOURCE_RANGES_KEY]
        if not isinstance(ranges, dict):
            return f"switching.{SOURCE_RANGES_KEY} must be an object: column -> [min, max]"
        for column, pair in ranges.items():
            if not (
                isinstance(pair, list) and len(pair) == 2 and all(_is_number(v) for v in pair) and pair[0] <= pair[1]
            ):
                return f"switching.{SOURCE_RANGES_KEY}['{column}'] must be [min, max] with min <= max"
    try:
        derived = derived_input_features(model)
    except InputError as exc:
        return str(exc)
    temps = model.get("temps", [])
    if 0 <= index < n_temps and temps[index] in derived:
        return (
            f"switching.criterion_index names the derived input '{temps[index]}'; "
            "the switching criterion must be a measured input"
        )
    return None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def complete_rule_section(model: dict[str, Any]) -> dict[str, Any]:
    """The model's switching section with every rule key (derived when absent)."""
    section = dict(model["switching"])
    if "criterion_index" not in section:
        raise InputError("the model's switching section names no criterion_index; fit the model again")
    section.setdefault("criterion", model["temps"][section["criterion_index"]])
    if all(key in section for key in RULE_KEYS):
        return section
    if "criterion_series" not in section:
        raise InputError(
            "the model's switching section has neither the rule parameters nor the criterion_series "
            "to derive them from; fit the model again"
        )
    derived = rule_parameters(model, None, criterion_index=int(section["criterion_index"]))
    return {**derived, **section}


@dataclass(frozen=True)
class DerivedTable:
    """One derived input as the run-time rule computes it.

    Attributes
    ----------
    name, column, transform : str
        As in the model file's ``derived_inputs`` (:class:`groupfit.features.Feature`).
    reading : int
        0-based index of the source column among the rule's readings.
    input_index : int
        0-based index of the derived input among the model's inputs.
    tau_s : float or None
        Low-pass time constant (s).
    delay_samples : int
        Length of a delay line (samples); 0 for the other transforms.
    a, b : float
        Low-pass coefficients ``a = e^{−Δt/τ}`` (computed as
        :func:`groupfit.features.lowpass` does) and ``b = 1 − a``; 0 otherwise.
    scale : float
        Derivative factor ``3600/Δt`` (per hour); 0 otherwise.
    """

    name: str
    column: str
    transform: str
    reading: int
    input_index: int
    tau_s: float | None
    delay_samples: int
    a: float
    b: float
    scale: float

    def describe(self) -> str:
        """Words for headers and sheets, ASCII only."""
        if self.transform == "lowpass":
            return f"low-pass of {self.column}, tau = {self.tau_s:g} s"
        if self.transform == "derivative":
            return f"time derivative of {self.column}, per hour"
        if self.transform == "delay":
            return f"{self.column} delayed by {self.delay_samples} sample(s)"
        return f"{self.column} as read"


@dataclass(frozen=True)
class RuleTables:
    """Every number the run-time rule uses, in the form every target embeds.

    Built once from a model file object; the Python rule and every export
    read these same tables.

    The rule's *readings* (``raw_names``) are what a caller passes per
    sample: the model's measured inputs in model order, then the source
    columns of its derived inputs that are not among them. The model's
    *inputs* (``input_names``, one coefficient each) are those readings and
    the derived inputs computed from them.
    """

    raw_names: tuple[str, ...]
    """The readings, in the order the rule takes them."""
    input_names: tuple[str, ...]
    """The model's inputs (``temps`` of the model file), in coefficient order."""
    input_reading: tuple[int, ...]
    """Per model input: the 0-based reading it is, or −1 for a derived input."""
    input_derived: tuple[int, ...]
    """Per model input: the 0-based derived input it is, or −1 for a measured one."""
    derived: tuple[DerivedTable, ...]
    criterion: str
    criterion_index: int
    """0-based model input of the criterion (always a measured input)."""
    criterion_reading: int
    """0-based reading of the criterion."""
    sampling_period_s: float
    period_tolerance: float
    coefficients: np.ndarray = field(repr=False)
    """(G, M+1): constant first, then one coefficient per model input."""
    window_first: tuple[int, ...]
    window_last: tuple[int, ...]
    directions: tuple[int, ...]
    thresholds_c: tuple[float, ...]
    margin_c: float
    hold_samples: int
    valid_min: tuple[float, ...]
    """Per reading: the smallest valid value (°C for temperatures, the column's unit for sources)."""
    valid_max: tuple[float, ...]
    valid_origin: tuple[str, ...]
    """Per reading: where its range comes from: ``"temperature"``, ``"source"`` or ``"fallback"``."""
    comp_min_um: float
    comp_max_um: float
    rate_limit_um: float
    breaks: tuple[int, ...]
    n: int
    error_name: str | None

    @classmethod
    def from_model(cls, model: dict[str, Any]) -> "RuleTables":
        section = complete_rule_section(model)
        coefficients = coefficient_matrix(model)
        windows = section["windows"]
        input_names = tuple(model["temps"])
        features = derived_input_features(model)
        measured = [name for name in input_names if name not in features]
        raw = list(measured)
        for name in input_names:
            if name in features and features[name].column not in raw:
                raw.append(features[name].column)
        period = float(model["sampling_period_s"])
        derived = []
        for name in input_names:
            if name not in features:
                continue
            feature = features[name]
            a = float(np.exp(-period / feature.tau_s)) if feature.transform == "lowpass" else 0.0
            derived.append(
                DerivedTable(
                    name=name,
                    column=feature.column,
                    transform=feature.transform,
                    reading=raw.index(feature.column),
                    input_index=input_names.index(name),
                    tau_s=float(feature.tau_s) if feature.transform == "lowpass" else None,
                    delay_samples=int(feature.delay_samples) if feature.transform == "delay" else 0,
                    a=a,
                    b=float(1.0 - a) if feature.transform == "lowpass" else 0.0,
                    scale=DERIVATIVE_SCALE_S / period if feature.transform == "derivative" else 0.0,
                )
            )
        derived_index = {d.name: k for k, d in enumerate(derived)}
        criterion_index = int(section["criterion_index"])
        if input_names[criterion_index] in features:
            raise InputError(
                f"the switching criterion '{input_names[criterion_index]}' is a derived input; "
                "it must be a measured input"
            )
        ranges = section.get(SOURCE_RANGES_KEY, {})
        valid_min, valid_max, origin = [], [], []
        for r, name in enumerate(raw):
            if r < len(measured):
                j = input_names.index(name)
                low, high, where = section["temp_min_c"][j], section["temp_max_c"][j], "temperature"
            elif name in ranges:
                (low, high), where = ranges[name], "source"
            else:
                (low, high), where = LEGACY_SOURCE_RANGE, "fallback"
            valid_min.append(float(low))
            valid_max.append(float(high))
            origin.append(where)
        return cls(
            raw_names=tuple(raw),
            input_names=input_names,
            input_reading=tuple(raw.index(n) if n not in features else -1 for n in input_names),
            input_derived=tuple(derived_index.get(n, -1) for n in input_names),
            derived=tuple(derived),
            criterion=str(section["criterion"]),
            criterion_index=criterion_index,
            criterion_reading=raw.index(input_names[criterion_index]),
            sampling_period_s=period,
            period_tolerance=float(section["period_tolerance"]),
            coefficients=coefficients,
            window_first=tuple(int(w[0]) for w in windows),
            window_last=tuple(int(w[1]) for w in windows),
            directions=tuple(int(d) for d in section["directions"]),
            thresholds_c=tuple(float(v) for v in section["thresholds_c"]),
            margin_c=float(section["margin_c"]),
            hold_samples=int(section["hold_samples"]),
            valid_min=tuple(valid_min),
            valid_max=tuple(valid_max),
            valid_origin=tuple(origin),
            comp_min_um=float(section["comp_min_um"]),
            comp_max_um=float(section["comp_max_um"]),
            rate_limit_um=float(section["rate_limit_um"]),
            breaks=tuple(int(b) for b in model["breaks"]),
            n=int(model["n"]),
            error_name=model.get("error"),
        )

    @property
    def n_temps(self) -> int:
        """Number of readings per sample (the C routine's ``GF_N_TEMPS``)."""
        return len(self.raw_names)

    @property
    def n_inputs(self) -> int:
        """Number of model inputs (coefficients per group besides the constant)."""
        return len(self.input_names)

    @property
    def n_measured(self) -> int:
        """Readings that are model inputs themselves; the sources follow them."""
        return sum(1 for r in self.input_reading if r >= 0)

    @property
    def source_names(self) -> tuple[str, ...]:
        """Readings that only feed derived inputs."""
        return self.raw_names[self.n_measured :]

    @property
    def temp_names(self) -> tuple[str, ...]:
        """The readings (the name older callers use)."""
        return self.raw_names

    @property
    def temp_min_c(self) -> tuple[float, ...]:
        return self.valid_min

    @property
    def temp_max_c(self) -> tuple[float, ...]:
        return self.valid_max

    def uses_of(self, reading: int) -> list[str]:
        """What a reading feeds: its own model input and/or the derived inputs computed from it."""
        uses = []
        if reading < self.n_measured:
            uses.append(f"model input {self.input_reading.index(reading) + 1}")
        uses.extend(f"source of derived input {d.name}" for d in self.derived if d.reading == reading)
        return uses

    @property
    def n_groups(self) -> int:
        return len(self.coefficients)

    @property
    def n_windows(self) -> int:
        return len(self.window_first)

    @property
    def period_tolerance_s(self) -> float:
        """Largest accepted difference between the live and the model's sampling period (s)."""
        return self.period_tolerance * self.sampling_period_s


@dataclass(frozen=True)
class StepResult:
    """What the rule decides for one sample.

    Attributes
    ----------
    group : int
        1-based group serving this sample (tracked through faults too).
    prediction_um : float
        Predicted thermal error (0 under a sensor fault).
    compensation_um : float
        Value for the controller: −prediction, clamped and rate-limited.
    fault : int
        Bit mask: :data:`FAULT_HELD` (1), :data:`FAULT_SENSOR` (2).
    switched : int
        0, or :data:`SWITCH_CRITERION` / :data:`SWITCH_FORCED` when the group
        advanced at this sample.
    """

    group: int
    prediction_um: float
    compensation_um: float
    fault: int
    switched: int = SWITCH_NONE

    @property
    def code(self) -> int:
        """What the exported step routines return: the group, or :data:`RETURN_SENSOR_FAULT`."""
        return RETURN_SENSOR_FAULT if self.fault & FAULT_SENSOR else self.group


@dataclass(frozen=True)
class Replay:
    """A run replayed sample by sample (arrays of length N)."""

    group: np.ndarray
    prediction_um: np.ndarray
    compensation_um: np.ndarray
    fault: np.ndarray
    switched: np.ndarray

    def switch_samples(self) -> list[dict[str, int | bool]]:
        """Every switch: 1-based sample, groups before and after, whether it was forced."""
        out = []
        for i in np.flatnonzero(self.switched):
            out.append(
                {
                    "i": int(i) + 1,
                    "from": int(self.group[i]) - 1,
                    "to": int(self.group[i]),
                    "forced": bool(self.switched[i] == SWITCH_FORCED),
                }
            )
        return out


class SwitchingRule:
    """The run-time rule: one call of :meth:`step` per sample.

    Parameters
    ----------
    model : dict
        A model file object (:func:`groupfit.modelfile.load_model`).
    precision : {"double", "single"}
        Double, or IEEE single precision computed operation for operation as
        the C build with ``GF_USE_FLOAT`` and a PLC's REAL compute it.
    period_s : float, optional
        The live run's sampling period; refused (InputError) when it differs
        from the model's by more than ``period_tolerance``.
    """

    def __init__(self, model: dict[str, Any], *, precision: str = "double", period_s: float | None = None):
        if precision not in ("double", "single"):
            raise ValueError(f"precision must be 'double' or 'single', got {precision!r}")
        self.tables = RuleTables.from_model(model)
        self.precision = precision
        if period_s is not None:
            check_period(self.tables, period_s)
        real = np.float32 if precision == "single" else float
        t = self.tables
        self._real = real
        self._coef = [[real(v) for v in row] for row in t.coefficients]
        self._threshold = [real(v) for v in t.thresholds_c]
        self._margin = real(t.margin_c)
        self._comp_min = real(t.comp_min_um)
        self._comp_max = real(t.comp_max_um)
        self._rate = real(t.rate_limit_um)
        self._zero = real(0.0)
        self._lp_a = [real(d.a) for d in t.derived]
        self._lp_b = [real(d.b) for d in t.derived]
        self._scale = [real(d.scale) for d in t.derived]
        self.reset()

    def reset(self) -> None:
        """Back to the first sample: group 1, no good readings yet, derived inputs not started, compensation 0."""
        t = self.tables
        self.count = 0
        self.group = 1
        self.bad = [t.hold_samples + 1] * t.n_temps
        self.last = [self._zero] * t.n_temps
        self.compensation = self._zero
        self.started = [False] * len(t.derived)
        self.memory = [self._zero] * len(t.derived)
        self.derived = [self._zero] * len(t.derived)
        self.lines = [[self._zero] * d.delay_samples for d in t.derived]
        self.positions = [0] * len(t.derived)

    def step(self, temps: Sequence[float]) -> StepResult:
        """Process one sample of readings (the model's measured inputs, then the sources, see :attr:`tables`)."""
        t = self.tables
        if len(temps) != t.n_temps:
            raise InputError(f"{len(temps)} readings given; the model takes {t.n_temps} ({', '.join(t.raw_names)})")
        if self.count < COUNT_MAX:
            self.count += 1
        held = faulted = False
        for m in range(t.n_temps):
            reading = float(temps[m])
            if reading >= t.valid_min[m] and reading <= t.valid_max[m]:
                self.last[m] = self._real(reading)
                self.bad[m] = 0
            elif self.bad[m] <= t.hold_samples:
                self.bad[m] += 1
            if self.bad[m] > t.hold_samples:
                faulted = True
            elif self.bad[m] > 0:
                held = True
        for k in range(len(t.derived)):
            self._derive(k)

        switched = SWITCH_NONE
        if self.group < t.n_groups:
            w = self.group - 1
            if self.count >= t.window_last[w]:
                self.group += 1
                switched = SWITCH_FORCED
            elif self.count >= t.window_first[w] and self._criterion_passes(w):
                self.group += 1
                switched = SWITCH_CRITERION

        if faulted:
            prediction = self._zero
            target = self._zero
        else:
            row = self._coef[self.group - 1]
            prediction = row[0]
            for j in range(t.n_inputs):
                r = t.input_reading[j]
                value = self.last[r] if r >= 0 else self.derived[t.input_derived[j]]
                prediction = prediction + row[j + 1] * value
            target = -prediction
        if target > self._comp_max:
            target = self._comp_max
        if target < self._comp_min:
            target = self._comp_min
        delta = target - self.compensation
        if delta > self._rate:
            delta = self._rate
        if delta < -self._rate:
            delta = -self._rate
        self.compensation = self.compensation + delta
        fault = (FAULT_HELD if held else 0) + (FAULT_SENSOR if faulted else 0)
        return StepResult(self.group, float(prediction), float(self.compensation), fault, switched)

    def _derive(self, k: int) -> None:
        """Advance derived input ``k`` by one sample from its source's last good value."""
        d = self.tables.derived[k]
        x = self.last[d.reading]
        if d.transform == "identity":
            self.derived[k] = x
            return
        if not self.started[k] and self.bad[d.reading] == 0:
            self.started[k] = True
            if d.transform == "delay":
                self.lines[k] = [x] * d.delay_samples
                self.positions[k] = 0
            else:
                self.memory[k] = x
        if not self.started[k]:
            return
        if d.transform == "lowpass":
            self.memory[k] = self._lp_b[k] * x + self._lp_a[k] * self.memory[k]
            self.derived[k] = self.memory[k]
        elif d.transform == "derivative":
            self.derived[k] = (x - self.memory[k]) * self._scale[k]
            self.memory[k] = x
        else:
            line, position = self.lines[k], self.positions[k]
            self.derived[k] = line[position]
            line[position] = x
            position += 1
            if position >= d.delay_samples:
                position = 0
            self.positions[k] = position

    def input_values(self) -> list[float]:
        """The model's inputs at the last sample: held readings and derived inputs."""
        t = self.tables
        return [
            float(self.last[r] if r >= 0 else self.derived[t.input_derived[j]]) for j, r in enumerate(t.input_reading)
        ]

    def _criterion_passes(self, w: int) -> bool:
        t = self.tables
        c = t.criterion_reading
        direction = t.directions[w]
        if self.bad[c] > t.hold_samples or direction == 0:
            return True
        difference = self.last[c] - self._threshold[w]
        if direction > 0:
            return bool(difference >= -self._margin)
        return bool(difference <= self._margin)

    def replay(self, temps_matrix) -> Replay:
        """Reset, then step through every row of an (N, k) array of readings."""
        temps_matrix = np.asarray(temps_matrix, dtype=float)
        if temps_matrix.ndim != 2 or temps_matrix.shape[1] != self.tables.n_temps:
            raise InputError(
                f"readings of shape {temps_matrix.shape}: the model takes {self.tables.n_temps} columns "
                f"({', '.join(self.tables.raw_names)})"
            )
        self.reset()
        n_samples = len(temps_matrix)
        group = np.empty(n_samples, dtype=int)
        fault = np.empty(n_samples, dtype=int)
        switched = np.empty(n_samples, dtype=int)
        prediction = np.empty(n_samples)
        compensation = np.empty(n_samples)
        for i, row in enumerate(temps_matrix.tolist()):
            result = self.step(row)
            group[i], fault[i], switched[i] = result.group, result.fault, result.switched
            prediction[i], compensation[i] = result.prediction_um, result.compensation_um
        return Replay(group, prediction, compensation, fault, switched)


def replay_groups(model: dict[str, Any], inputs) -> np.ndarray:
    """0-based group the run-time rule serves at each row of the model's inputs (double precision).

    For comparisons that score a grouped model on another run through the
    rule a controller would run, rather than by sample index. ``inputs`` is
    the (N, M) matrix of the model's inputs, derived ones included (as
    :func:`groupfit.diagnose.residual.model_inputs` computes them). The group
    depends only on the sample count and the criterion, a measured input, so
    the rule is replayed on the measured inputs, with every source column
    that is not a model input held at a valid value.
    """
    rule = SwitchingRule(model)
    t = rule.tables
    inputs = np.asarray(inputs, dtype=float)
    if not t.derived:
        return rule.replay(inputs).group - 1
    if inputs.ndim != 2 or inputs.shape[1] != t.n_inputs:
        raise InputError(f"model inputs of shape {inputs.shape}: the model has {t.n_inputs} inputs")
    readings = np.empty((len(inputs), t.n_temps))
    for j, r in enumerate(t.input_reading):
        if r >= 0:
            readings[:, r] = inputs[:, j]
    for r in range(t.n_measured, t.n_temps):
        readings[:, r] = t.valid_min[r]
    return rule.replay(readings).group - 1


def check_period(tables: RuleTables, period_s: float) -> None:
    """Refuse a live sampling period that differs from the model's."""
    if not (abs(period_s - tables.sampling_period_s) <= tables.period_tolerance_s):
        raise InputError(
            f"sampling period {period_s:g} s differs from the model's {tables.sampling_period_s:g} s "
            f"(tolerance {100 * tables.period_tolerance:g} %): the rule counts samples, so resample the run "
            "to the model's period or fit a model at this period"
        )


__all__ = [
    "DerivedTable",
    "RuleSettings",
    "RuleTables",
    "Replay",
    "StepResult",
    "SwitchingRule",
    "check_period",
    "complete_rule_section",
    "derived_input_features",
    "replay_groups",
    "rule_parameters",
    "rule_section_problem",
    "source_ranges",
    "source_valid_range",
    "switch_windows",
]
