"""The run-time rule's tables: every number the rule uses, in the form every target embeds.

A derived input with a power stage (:attr:`DerivedTable.exponent`) maps its
source's value ``v`` to ``(|v| / power_scale)^exponent`` before its transform,
computed in double precision in every mode and every target (``fabs`` and the
C library's ``pow``; Python's :func:`math.pow` calls the same ``pow``); single
precision rounds the result to IEEE single once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from groupfit.errors import InputError
from groupfit.features import HOURS_PER_S
from groupfit.model import ModelFile
from groupfit.reference import START, is_column_reference
from groupfit.runtime.recalibration import RecalTable, model_section
from groupfit.runtime.rule import DERIVATIVE_SCALE_S, LEGACY_SOURCE_RANGE, complete_rule_section


def derived_scale(transform: str, period: float) -> float:
    """The factor of a derivative (``3600/Δt``, per hour) or the step of an on-time (``Δt/3600``, hours); else 0."""
    if transform == "derivative":
        return DERIVATIVE_SCALE_S / period
    if transform == "ontime":
        return period * HOURS_PER_S
    return 0.0


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
        Derivative factor ``3600/Δt`` (per hour); on-time step ``Δt/3600``
        (hours per sample); 0 otherwise.
    exponent, power_scale : float or None
        The power stage ``v → (|v| / power_scale)^exponent`` applied to the
        source's value before the transform (the file's ``exponent`` and
        ``scale``); None without one. Computed in double precision in every
        mode: a single-precision rule widens its float32 value to double,
        takes ``pow(fabs(v) / power_scale, exponent)`` and rounds the result to
        float32 once.
    start : {"steady", "rest"}
        Where a low-pass or a delay starts at the source's first good reading:
        ``"steady"``: its state is that value (low-pass output, every entry of
        the delay line); ``"rest"``: its state is 0 (the source was off before
        the run), so the first low-pass output is ``b·v``. Always
        ``"steady"`` for identity and derivative, which it does not affect,
        and ``"rest"`` for an on-time (its count starts at 0).
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
    exponent: float | None = None
    power_scale: float | None = None
    start: str = "steady"

    @property
    def has_power(self) -> bool:
        """Whether the source's value passes the power stage first."""
        return self.exponent is not None

    @property
    def from_rest(self) -> bool:
        """Whether a low-pass or a delay starts from 0 rather than from the first good value."""
        return self.start == "rest"

    def transform_constants(self) -> tuple[tuple[str, float], ...]:
        """The transform's constants every target embeds, by name: the low-pass ``a`` and ``b``, the
        derivative's scale, the on-time step; none for identity and delay."""
        constants = {
            "lowpass": (("lowpass_a", self.a), ("lowpass_b", self.b)),
            "derivative": (("derivative_scale", self.scale),),
            "ontime": (("ontime_step", self.scale),),
        }
        return constants.get(self.transform, ())

    def power_text(self) -> str:
        """The power stage in words (ASCII), e.g. ``(|spindle_rpm| / 1000)^1.66667``; the column without one."""
        if not self.has_power:
            return self.column
        return f"(|{self.column}| / {self.power_scale:g})^{self.exponent:.6g}"

    def describe(self) -> str:
        """Words for headers and sheets, ASCII only."""
        source = self.power_text()
        rest = ", from rest" if self.from_rest else ""
        if self.transform == "lowpass":
            return f"low-pass of {source}, tau = {self.tau_s:g} s{rest}"
        if self.transform == "derivative":
            return f"time derivative of {source}, per hour"
        if self.transform == "delay":
            return f"{source} delayed by {self.delay_samples} sample(s){rest}"
        if self.transform == "ontime":
            return f"{source} times the hours it has been non-zero"
        return f"{source} (heat law)" if self.has_power or self.from_rest else f"{source} as read"

    def power(self, value: float) -> float:
        """The power stage of a source value, in double precision (the C library's ``pow``, as C calls it)."""
        return math.pow(math.fabs(value) / self.power_scale, self.exponent)


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
    reference: str | None = None
    """The model's reference (:mod:`groupfit.reference`): a column, ``"start"`` or None."""
    reference_reading: int = -1
    """0-based reading of a reference column (one more reading, after the sources), or −1."""
    dead_band_reading: int = -1
    """0-based reading of the dead band's reference sensor, or −1 without a dead band."""
    dead_band_c: float = 0.0
    """Dead band (°C): no update while every measured input is within it of the dead band's reference."""
    position_reading: int = -1
    """0-based reading of the axis position (mm; the last reading), or −1 without a position model."""
    position_name: str | None = None
    p0_mm: float = 0.0
    travel_min_mm: float = 0.0
    travel_max_mm: float = 0.0
    position_coefficients: np.ndarray | None = field(default=None, repr=False)
    """(G, order, M+1): per group the rows of c_1 … c_order (constant first), or None."""
    recalibration: RecalTable | None = None
    """The probe-check filter (:mod:`groupfit.runtime.recalibration`); the default hold without a section."""
    blend_samples: int = 0
    """Bumpless transfer after a switch: for this many samples the prediction is the old group's moved
    towards the new group's, by ``k / (blend_samples + 1)`` at the switch's k-th sample; 0: a hard switch."""

    @classmethod
    def from_model(cls, model: ModelFile | Mapping[str, Any]) -> "RuleTables":
        model = ModelFile.coerce(model)
        section = complete_rule_section(model)
        coefficients = model.coefficient_matrix()
        windows = section.windows
        input_names = tuple(model.temps)
        features = model.derived
        measured = [name for name in input_names if name not in features]
        raw = list(measured)
        for name in input_names:
            if name in features and features[name].column not in raw:
                raw.append(features[name].column)
        raw += reference_readings(model, raw)
        if model.dead_band is not None and model.dead_band.reference not in raw:
            raw.append(model.dead_band.reference)
        if model.position is not None:
            raw.append(model.position.column)
        period = float(model.sampling_period_s)
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
                    scale=derived_scale(feature.transform, period),
                    exponent=None if feature.exponent is None else float(feature.exponent),
                    power_scale=None if feature.exponent is None else float(feature.scale),
                    start=feature.start if feature.transform in ("lowpass", "delay", "ontime") else "steady",
                )
            )
        derived_index = {d.name: k for k, d in enumerate(derived)}
        criterion_index = int(section.criterion_index)
        if input_names[criterion_index] in features:
            raise InputError(
                f"the switching criterion '{input_names[criterion_index]}' is a derived input; "
                "it must be a measured input"
            )
        ranges = section.source_ranges or {}
        valid_min, valid_max, origin = [], [], []
        for r, name in enumerate(raw):
            if r < len(measured):
                j = input_names.index(name)
                low, high, where = section.temp_min_c[j], section.temp_max_c[j], "temperature"
            elif model.position is not None and name == model.position.column:
                (low, high), where = LEGACY_SOURCE_RANGE, "position"
            elif name in ranges:
                (low, high), where = ranges[name], "source"
            else:
                (low, high), where = LEGACY_SOURCE_RANGE, "fallback"
            valid_min.append(float(low))
            valid_max.append(float(high))
            origin.append(where)
        for d in derived:
            _check_power_range(d, valid_min[d.reading], valid_max[d.reading])
        return cls(
            raw_names=tuple(raw),
            input_names=input_names,
            input_reading=tuple(raw.index(n) if n not in features else -1 for n in input_names),
            input_derived=tuple(derived_index.get(n, -1) for n in input_names),
            derived=tuple(derived),
            criterion=str(section.criterion),
            criterion_index=criterion_index,
            criterion_reading=raw.index(input_names[criterion_index]),
            sampling_period_s=period,
            period_tolerance=float(section.period_tolerance),
            coefficients=coefficients,
            window_first=tuple(int(w[0]) for w in windows),
            window_last=tuple(int(w[1]) for w in windows),
            directions=tuple(int(d) for d in section.directions),
            thresholds_c=tuple(float(v) for v in section.thresholds_c),
            margin_c=float(section.margin_c),
            hold_samples=int(section.hold_samples),
            valid_min=tuple(valid_min),
            valid_max=tuple(valid_max),
            valid_origin=tuple(origin),
            comp_min_um=float(section.comp_min_um),
            comp_max_um=float(section.comp_max_um),
            rate_limit_um=float(section.rate_limit_um),
            breaks=tuple(int(b) for b in model.breaks),
            n=int(model.n),
            error_name=model.error,
            reference=model.reference,
            reference_reading=raw.index(model.reference) if is_column_reference(model.reference) else -1,
            blend_samples=int(section.blend_samples or 0),
            **_position_tables(model, raw),
            recalibration=RecalTable.from_section(
                model_section(
                    model,
                    comp_limit_um=max(-float(section.comp_min_um), float(section.comp_max_um)),
                    rate_limit_um=float(section.rate_limit_um),
                ),
                period,
            ),
        )

    @property
    def correction_bound_um(self) -> float:
        """How far probe checks may carry the compensation beyond the model's clamp (µm): the offset's bound."""
        return float(self.recalibration.x_max[0]) if self.recalibration is not None else 0.0

    @property
    def output_min_um(self) -> float:
        """The output's lower bound: the model's clamp widened by :attr:`correction_bound_um`."""
        return self.comp_min_um - self.correction_bound_um

    @property
    def output_max_um(self) -> float:
        """The output's upper bound: the model's clamp widened by :attr:`correction_bound_um`."""
        return self.comp_max_um + self.correction_bound_um

    @property
    def output_bounds(self) -> dict[str, float]:
        """The model's clamp, the output's bounds and the rate limit (µm, µm per sample), by the names the
        exports use."""
        return {
            "comp_min": self.comp_min_um,
            "comp_max": self.comp_max_um,
            "out_min": self.output_min_um,
            "out_max": self.output_max_um,
            "rate": self.rate_limit_um,
        }

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

    def uses_of(self, reading: int) -> list[str]:
        """What a reading feeds: its own model input and/or the derived inputs computed from it."""
        uses = []
        if reading < self.n_measured:
            uses.append(f"model input {self.input_reading.index(reading) + 1}")
        uses.extend(f"source of derived input {d.name}" for d in self.derived if d.reading == reading)
        if reading == self.reference_reading:
            uses.append("reference of every measured input")
        if reading == self.dead_band_reading:
            uses.append("reference of the dead band")
        if reading == self.position_reading:
            uses.append("axis position (mm) of the position terms")
        return uses

    @property
    def n_groups(self) -> int:
        return len(self.coefficients)

    @property
    def position_order(self) -> int:
        """Highest power of ``P − P0`` (0 without a position model)."""
        return 0 if self.position_coefficients is None else int(self.position_coefficients.shape[1])

    @property
    def has_position(self) -> bool:
        return self.position_reading >= 0

    @property
    def has_dead_band(self) -> bool:
        return self.dead_band_reading >= 0

    # ----------------------------------------------------------------- reference temperature

    @property
    def reference_start(self) -> bool:
        """Whether every measured input is taken relative to its own first good reading."""
        return self.reference == START

    @property
    def n_windows(self) -> int:
        return len(self.window_first)

    @property
    def period_tolerance_s(self) -> float:
        """Largest accepted difference between the live and the model's sampling period (s)."""
        return self.period_tolerance * self.sampling_period_s


POWER_MAX = 1e30
"""Largest power-stage value a valid source reading may produce (far inside IEEE single precision)."""


def _check_power_range(d: DerivedTable, low: float, high: float) -> None:
    """Refuse a power stage that overflows within its source's valid range (no target may meet inf or UB)."""
    if not d.has_power:
        return
    try:
        top = d.power(max(abs(low), abs(high)))
    except OverflowError:
        top = math.inf
    if not top <= POWER_MAX:
        raise InputError(
            f"derived input {d.name}: its power stage reaches {top:g} within the valid range "
            f"[{low:g}, {high:g}] of '{d.column}' (at most {POWER_MAX:g}); narrow the range or change the scale"
        )


def _position_tables(model: ModelFile, raw: list[str]) -> dict[str, Any]:
    """The position and dead-band fields of :class:`RuleTables` (defaults without them)."""
    out: dict[str, Any] = {}
    if model.dead_band is not None:
        out.update(
            dead_band_reading=raw.index(model.dead_band.reference), dead_band_c=float(model.dead_band.threshold_c)
        )
    position = model.position
    if position is not None:
        out.update(
            position_reading=raw.index(position.column),
            position_name=position.column,
            p0_mm=float(position.p0_mm),
            travel_min_mm=float(position.travel_mm[0]),
            travel_max_mm=float(position.travel_mm[1]),
            position_coefficients=position.coefficient_array(intercept=model.intercept),
        )
    return out


def reference_readings(model: ModelFile, raw: list[str]) -> list[str]:
    """The reference column as one more reading, unless it already is one (a source of a derived input)."""
    if is_column_reference(model.reference) and model.reference not in raw:
        return [str(model.reference)]
    return []
