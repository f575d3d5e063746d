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
* ``delay``: ``x[k − d]``, ``x[0]`` before the run.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from groupfit.errors import InputError

TRANSFORMS = ("identity", "lowpass", "derivative", "delay")


@dataclass(frozen=True)
class Feature:
    """A column and the transform applied to it."""

    column: str
    transform: str = "identity"
    tau_s: float | None = None
    delay_samples: int = 0

    def __post_init__(self):
        if self.transform not in TRANSFORMS:
            raise InputError(f"transform {self.transform!r}: choose one of {', '.join(TRANSFORMS)}")
        if self.transform == "lowpass" and not (self.tau_s and self.tau_s > 0):
            raise InputError(f"low-pass of '{self.column}' needs a time constant tau_s > 0")
        if self.transform == "delay" and self.delay_samples < 1:
            raise InputError(f"delay of '{self.column}' needs delay_samples >= 1")

    @property
    def name(self) -> str:
        """A column name for the derived input, e.g. ``T_amb~lp7200s``."""
        if self.transform == "lowpass":
            return f"{self.column}~lp{self.tau_s:g}s"
        if self.transform == "derivative":
            return f"{self.column}~ddt"
        if self.transform == "delay":
            return f"{self.column}~delay{self.delay_samples}"
        return self.column

    def describe(self) -> str:
        """Words for a report: ``low-pass τ = 2 h``."""
        if self.transform == "lowpass":
            hours = self.tau_s / 3600.0
            return f"low-pass τ = {hours:.3g} h" if hours >= 1 else f"low-pass τ = {self.tau_s / 60:.3g} min"
        if self.transform == "derivative":
            return "time derivative (per hour)"
        if self.transform == "delay":
            return f"delay {self.delay_samples} samples"
        return "as measured"

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, **asdict(self)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Feature":
        return cls(
            column=data["column"],
            transform=data.get("transform", "identity"),
            tau_s=data.get("tau_s"),
            delay_samples=int(data.get("delay_samples", 0)),
        )

    def compute(self, values: np.ndarray, period_s: float) -> np.ndarray:
        """The derived series of a column sampled every ``period_s`` seconds."""
        x = np.asarray(values, dtype=float)
        if self.transform == "identity":
            return x.copy()
        if self.transform == "derivative":
            return np.r_[0.0, np.diff(x)] * (3600.0 / period_s)
        if self.transform == "delay":
            d = min(self.delay_samples, len(x))
            return np.r_[np.full(d, x[0]), x[: len(x) - d]]
        return lowpass(x, self.tau_s, period_s)


def lowpass(x: np.ndarray, tau_s: float, period_s: float) -> np.ndarray:
    """First-order lag ``y[k] = a·y[k−1] + (1 − a)·x[k]``, started at ``x[0]``."""
    from scipy.signal import lfilter

    x = np.asarray(x, dtype=float)
    a = np.exp(-period_s / tau_s)
    y, _ = lfilter([1.0 - a], [1.0, -a], x, zi=[a * x[0]])
    return y


def derived_matrix(features: list[Feature], frame, period_s: float) -> np.ndarray:
    """Columns of derived inputs from a table (DataFrame-like, by column name)."""
    columns = []
    for feature in features:
        if feature.column not in frame.columns:
            raise InputError(f"the model needs column '{feature.column}' for its input {feature.name}; it is missing")
        columns.append(feature.compute(frame[feature.column].to_numpy(dtype=float), period_s))
    return np.column_stack(columns) if columns else np.empty((len(frame), 0))
