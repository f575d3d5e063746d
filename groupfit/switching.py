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
good reading of every sensor and how many samples ago it was good, and the
compensation value last handed to the controller.

1. ``i ← i + 1`` (saturating at :data:`COUNT_MAX`).
2. Every reading is *valid* when ``temp_min_c ≤ x ≤ temp_max_c`` (NaN and
   ±inf never are). A valid reading replaces the sensor's last good value; an
   invalid one keeps it and counts a bad sample. Up to ``hold_samples`` (K)
   bad samples in a row are *held* (fault bit 1, the output stays valid);
   more, or a bad reading before any good one, is a *sensor fault*
   (fault bit 2).
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
4. Prediction ``ŷ = c₀ + Σ c_m·x_m`` of the current group with the held
   readings, accumulated in sensor order; under a sensor fault ``ŷ = 0``
   (the safe output: no compensation).
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
class RuleTables:
    """Every number the run-time rule uses, in the form every target embeds.

    Built once from a model file object; the Python rule and every export
    read these same tables.
    """

    temp_names: tuple[str, ...]
    criterion: str
    criterion_index: int
    sampling_period_s: float
    period_tolerance: float
    coefficients: np.ndarray = field(repr=False)
    """(G, M+1): constant first, then one coefficient per temperature."""
    window_first: tuple[int, ...]
    window_last: tuple[int, ...]
    directions: tuple[int, ...]
    thresholds_c: tuple[float, ...]
    margin_c: float
    hold_samples: int
    temp_min_c: tuple[float, ...]
    temp_max_c: tuple[float, ...]
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
        return cls(
            temp_names=tuple(model["temps"]),
            criterion=str(section["criterion"]),
            criterion_index=int(section["criterion_index"]),
            sampling_period_s=float(model["sampling_period_s"]),
            period_tolerance=float(section["period_tolerance"]),
            coefficients=coefficients,
            window_first=tuple(int(w[0]) for w in windows),
            window_last=tuple(int(w[1]) for w in windows),
            directions=tuple(int(d) for d in section["directions"]),
            thresholds_c=tuple(float(v) for v in section["thresholds_c"]),
            margin_c=float(section["margin_c"]),
            hold_samples=int(section["hold_samples"]),
            temp_min_c=tuple(float(v) for v in section["temp_min_c"]),
            temp_max_c=tuple(float(v) for v in section["temp_max_c"]),
            comp_min_um=float(section["comp_min_um"]),
            comp_max_um=float(section["comp_max_um"]),
            rate_limit_um=float(section["rate_limit_um"]),
            breaks=tuple(int(b) for b in model["breaks"]),
            n=int(model["n"]),
            error_name=model.get("error"),
        )

    @property
    def n_temps(self) -> int:
        return len(self.temp_names)

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
        self.reset()

    def reset(self) -> None:
        """Back to the first sample: group 1, no good readings yet, compensation 0."""
        t = self.tables
        self.count = 0
        self.group = 1
        self.bad = [t.hold_samples + 1] * t.n_temps
        self.last = [self._zero] * t.n_temps
        self.compensation = self._zero

    def step(self, temps: Sequence[float]) -> StepResult:
        """Process one sample of temperatures (°C, in the model's input order)."""
        t = self.tables
        if len(temps) != t.n_temps:
            raise InputError(
                f"{len(temps)} temperatures given; the model takes {t.n_temps} ({', '.join(t.temp_names)})"
            )
        if self.count < COUNT_MAX:
            self.count += 1
        held = faulted = False
        for m in range(t.n_temps):
            reading = float(temps[m])
            if reading >= t.temp_min_c[m] and reading <= t.temp_max_c[m]:
                self.last[m] = self._real(reading)
                self.bad[m] = 0
            elif self.bad[m] <= t.hold_samples:
                self.bad[m] += 1
            if self.bad[m] > t.hold_samples:
                faulted = True
            elif self.bad[m] > 0:
                held = True

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
            for m in range(t.n_temps):
                prediction = prediction + row[m + 1] * self.last[m]
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

    def _criterion_passes(self, w: int) -> bool:
        t = self.tables
        c = t.criterion_index
        direction = t.directions[w]
        if self.bad[c] > t.hold_samples or direction == 0:
            return True
        difference = self.last[c] - self._threshold[w]
        if direction > 0:
            return bool(difference >= -self._margin)
        return bool(difference <= self._margin)

    def replay(self, temps_matrix) -> Replay:
        """Reset, then step through every row of an (N, k) temperature array."""
        temps_matrix = np.asarray(temps_matrix, dtype=float)
        if temps_matrix.ndim != 2 or temps_matrix.shape[1] != self.tables.n_temps:
            raise InputError(
                f"temperatures of shape {temps_matrix.shape}: the model takes {self.tables.n_temps} columns"
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


def replay_groups(model: dict[str, Any], temps) -> np.ndarray:
    """0-based group the run-time rule serves at each row of ``temps`` (double precision).

    For comparisons that score a grouped model on another run through the
    rule a controller would run, rather than by sample index.
    """
    return SwitchingRule(model).replay(temps).group - 1


def check_period(tables: RuleTables, period_s: float) -> None:
    """Refuse a live sampling period that differs from the model's."""
    if not (abs(period_s - tables.sampling_period_s) <= tables.period_tolerance_s):
        raise InputError(
            f"sampling period {period_s:g} s differs from the model's {tables.sampling_period_s:g} s "
            f"(tolerance {100 * tables.period_tolerance:g} %): the rule counts samples, so resample the run "
            "to the model's period or fit a model at this period"
        )


__all__ = [
    "RuleSettings",
    "RuleTables",
    "Replay",
    "StepResult",
    "SwitchingRule",
    "check_period",
    "complete_rule_section",
    "replay_groups",
    "rule_parameters",
    "rule_section_problem",
    "switch_windows",
]
