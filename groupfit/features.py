"""Derived inputs: physically meaningful transforms of a data column.

A thermal effect rarely shows in a column as it is: a part with its own heat
capacity follows a heat source or the ambient temperature with a lag, a
growing gradient follows the rate of change. Each :class:`Feature` names a
column and a transform, computed sample by sample with a recursion a
controller can run too:

* ``identity``: ``x[k]``;
* ``lowpass``: first-order lag with time constant τ,
  ``y[k] = a·y[k−1] + (1 − a)·x[k]``, ``a = e^{−Δt/τ}``, ``y[0] = x[0]``;
* ``derivative``: ``(x[k] − x[k−1]) / Δt`` per hour, ``y[0] = 0``;
* ``delay``: ``x[k − d]``, ``x[0]`` before the run;
* ``ontime``: ``x[k]·h[k]``, ``h[k]`` the hours the column has been non-zero
  without a break up to sample k (``n[k]·Δt/3600``, ``n[k]`` the samples
  counted, 0 while it is zero): a heat source's power times the time it has
  run, the early, still linear rise of a part it heats.

Where the recursion starts is the feature's ``start``: ``"steady"`` (the
default) takes the part as settled at the first reading (``y[−1] = x[0]``),
right for a lag of the ambient; ``"rest"`` takes the source as off before the
run (``y[−1] = 0``, a delay line of zeros), right for a lag of a heat source —
a controller starts with the machine, and a test starts from a cold machine.
An on-time always starts from rest: its count begins at the first reading.

A feature may first raise its column to a power, ``(|x| / scale)^exponent``:
bearing heat grows with spindle speed as ``n^{5/3}`` (Palmgren's friction
moment times the speed), so a part heated by the bearings follows a low-pass
of ``(n / 1000)^{5/3}`` rather than of ``n``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from groupfit.errors import InputError

TRANSFORMS = ("identity", "lowpass", "derivative", "delay", "ontime")
HOURS_PER_S = 1.0 / 3600.0
"""An on-time is counted in hours."""
STARTS = ("steady", "rest")


@dataclass(frozen=True)
class Feature:
    """A column and the transform applied to it."""

    column: str
    transform: str = "identity"
    tau_s: float | None = None
    delay_samples: int = 0
    exponent: float | None = None
    scale: float | None = None
    start: str = "steady"

    def __post_init__(self):
        if self.start not in STARTS:
            raise InputError(f"start {self.start!r} of '{self.column}': choose one of {', '.join(STARTS)}")
        if self.transform not in TRANSFORMS:
            raise InputError(f"transform {self.transform!r}: choose one of {', '.join(TRANSFORMS)}")
        if self.transform == "lowpass" and not (self.tau_s and self.tau_s > 0):
            raise InputError(f"low-pass of '{self.column}' needs a time constant tau_s > 0")
        if self.transform == "delay" and self.delay_samples < 1:
            raise InputError(f"delay of '{self.column}' needs delay_samples >= 1")
        if self.transform != "delay" and self.delay_samples != 0:
            raise InputError(
                f"{self.transform} of '{self.column}': delay_samples = {self.delay_samples} belongs to a delay; "
                "leave it 0"
            )
        if self.transform == "ontime" and self.start != "rest":
            raise InputError(f"on-time of '{self.column}': it starts from rest (start 'rest')")
        if self.exponent is not None:
            if not (np.isfinite(self.exponent) and self.exponent > 0):
                raise InputError(f"power of '{self.column}': exponent {self.exponent!r} must be finite and > 0")
            if self.scale is None or not (np.isfinite(self.scale) and self.scale > 0):
                raise InputError(f"power of '{self.column}': scale {self.scale!r} must be finite and > 0")
        elif self.scale is not None:
            raise InputError(f"feature of '{self.column}': a scale is only used with an exponent")

    @property
    def source_name(self) -> str:
        """The column after the power stage, e.g. ``(spindle_rpm/1000)^1.667``."""
        if self.exponent is None:
            return self.column
        return f"({self.column}/{self.scale:g})^{self.exponent:.4g}"

    @property
    def name(self) -> str:
        """A column name for the derived input, e.g. ``T_amb~lp7200s``."""
        source = self.source_name
        rest = "r" if self.start == "rest" else ""
        if self.transform == "lowpass":
            return f"{source}~lp{self.tau_s:g}s{rest}"
        if self.transform == "derivative":
            return f"{source}~ddt"
        if self.transform == "delay":
            return f"{source}~delay{self.delay_samples}{rest}"
        if self.transform == "ontime":
            return f"{source}~ontime"
        return source

    def describe(self) -> str:
        """Words for a report: ``low-pass τ = 2 h``, ``heat law (n/1000)^1.67, low-pass τ = 30 min``."""
        if self.transform == "lowpass":
            hours = self.tau_s / 3600.0
            words = f"low-pass τ = {hours:.3g} h" if hours >= 1 else f"low-pass τ = {self.tau_s / 60:.3g} min"
        elif self.transform == "derivative":
            words = "time derivative (per hour)"
        elif self.transform == "delay":
            words = f"delay {self.delay_samples} samples"
        elif self.transform == "ontime":
            words = "times the hours on"
        else:
            words = "as measured"
        if self.start == "rest" and self.transform in ("lowpass", "delay"):
            words += ", from rest"
        if self.exponent is None:
            return words
        return f"heat law (x/{self.scale:g})^{self.exponent:.3g}, {words}"

    def to_dict(self) -> dict[str, Any]:
        data = {"name": self.name, **asdict(self)}
        if self.exponent is None:
            del data["exponent"], data["scale"]
        if self.start == "steady":
            del data["start"]
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Feature":
        return cls(
            column=data["column"],
            transform=data.get("transform", "identity"),
            tau_s=data.get("tau_s"),
            delay_samples=int(data.get("delay_samples", 0)),
            exponent=None if data.get("exponent") is None else float(data["exponent"]),
            scale=None if data.get("scale") is None else float(data["scale"]),
            start=data.get("start", "steady"),
        )

    def compute(self, values: np.ndarray, period_s: float) -> np.ndarray:
        """The derived series of a column sampled every ``period_s`` seconds."""
        x = np.asarray(values, dtype=float)
        if self.exponent is not None:
            x = power_stage(x, self.scale, self.exponent)
        if self.transform == "identity":
            return x.copy()
        if self.transform == "derivative":
            return np.r_[0.0, np.diff(x)] * (3600.0 / period_s)
        if self.transform == "ontime":
            return x * (on_counts(x) * (period_s * HOURS_PER_S))
        before = 0.0 if self.start == "rest" else x[0]
        if self.transform == "delay":
            d = min(self.delay_samples, len(x))
            return np.r_[np.full(d, before), x[: len(x) - d]]
        return lowpass(x, self.tau_s, period_s, before)


def on_counts(x: np.ndarray) -> np.ndarray:
    """Samples ``x`` has been non-zero without a break, up to and including each sample (0 where it is zero)."""
    on = np.asarray(x) != 0
    counts = np.cumsum(on, dtype=float)
    last_off = np.maximum.accumulate(np.where(on, 0.0, counts))
    return counts - last_off


def power_stage(x: np.ndarray, scale: float, exponent: float) -> np.ndarray:
    """``(|x| / scale)^exponent``, element by element.

    numpy's ``power`` may differ from the C library's ``pow`` in the last bit;
    the run-time rule and its exports use ``pow`` (:mod:`groupfit.runtime`).
    """
    return np.power(np.abs(np.asarray(x, dtype=float)) / scale, exponent)


def lowpass(x: np.ndarray, tau_s: float, period_s: float, before: float | None = None) -> np.ndarray:
    """First-order lag ``y[k] = a·y[k−1] + (1 − a)·x[k]`` with ``y[−1] = before`` (default ``x[0]``)."""
    from scipy.signal import lfilter

    x = np.asarray(x, dtype=float)
    a = np.exp(-period_s / tau_s)
    y, _ = lfilter([1.0 - a], [1.0, -a], x, zi=[a * (x[0] if before is None else before)])
    return y


def derived_matrix(features: list[Feature], frame, period_s: float, source: str = "the run") -> np.ndarray:
    """Columns of derived inputs from a table (DataFrame-like, by column name; ``source`` names it)."""
    columns = []
    for feature in features:
        if feature.column not in frame.columns:
            raise InputError(
                f"{source}: column '{feature.column}' not found; the model computes its input {feature.name} from it. "
                f"The columns are: {', '.join(map(str, frame.columns))}"
            )
        columns.append(feature.compute(frame[feature.column].to_numpy(dtype=float), period_s))
    return np.column_stack(columns) if columns else np.empty((len(frame), 0))
