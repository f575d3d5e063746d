"""The ball-screw model at run time: its law sample by sample, as ``replay`` runs it and the C export computes it.

The law of one heat source (docs/ballscrew.md, "At run time")::

    α′ = exp(interp(ln t, ln t_i, ln α′_i))     table law (ln t held at the table's ends)
       = max(a0 + a1·τ0, α_floor)               line law (τ0 the rise at the reference sensor)
    E(x, t) = 10⁶·a_m·x·Σ_k w_k·(C1·e^(−λ ξ_k) + C2·e^(λ ξ_k))·erfc((ξ_k + x0) / (2√(α′ t))),  ξ_k = x·u_k

with the model's own 256-point composite Gauss–Legendre rule (u_k, w_k) on
[0, 1]; E = 0 for t ≤ 0. Readings per sample: the time since the source came
on (s), the probe position x (m from the source) and, for the line law, τ0
(K). A non-finite reading, a negative x or (line law) a non-finite τ0 gives
the fault code −1 and no value.

:class:`ScrewLaw` evaluates it with Python's :mod:`math` (the C library's
``exp``, ``log``, ``erfc``, ``sqrt``) one operation after another in the
order the exported C performs them, so the two agree bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from groupfit.errors import InputError
from groupfit.screw.model import BallScrewModel
from groupfit.screw.physics import ALPHA_FLOOR, quadrature

FAULT_READING = -1
"""What the law returns for a sample whose readings it cannot use."""


def choose_source(model: BallScrewModel, source: str | None, label: str) -> str:
    """The heat source deployed: the one named, or the model's only one."""
    if source is None:
        if len(model.sources_) == 1:
            return next(iter(model.sources_))
        raise InputError(
            f"{label}: the model has the heat sources {', '.join(model.sources_)}; choose one with --source"
        )
    if source not in model.sources_:
        raise InputError(f"--source {source}: not in {label}; it has {', '.join(model.sources_)}")
    return source


@dataclass(frozen=True)
class ScrewLaw:
    """Every number of one source's run-time law (module docstring)."""

    source: str
    law: str
    c1: float
    c2: float
    lam: float
    x0: float
    expansion: float
    a0: float
    a1: float
    log_t: tuple[float, ...]
    log_alpha: tuple[float, ...]
    u: tuple[float, ...]
    w: tuple[float, ...]
    reference_x_m: float

    @classmethod
    def from_model(cls, model: BallScrewModel, source: str) -> "ScrewLaw":
        c1, c2 = model._source(source)
        times, alphas = getattr(model, "alpha_curve_", (np.ones(1), np.ones(1)))
        u, w = quadrature()
        return cls(
            source=source,
            law=model.alpha_law,
            c1=float(c1),
            c2=float(c2),
            lam=float(model.lambda_),
            x0=float(model.source_offset_),
            expansion=float(model.expansion),
            a0=float(model.alpha_prime_[0]),
            a1=float(model.alpha_prime_[1]),
            log_t=tuple(math.log(float(t)) for t in times),
            log_alpha=tuple(math.log(float(a)) for a in alphas),
            u=tuple(float(v) for v in u),
            w=tuple(float(v) for v in w),
            reference_x_m=float(model.reference_x_),
        )

    @property
    def readings(self) -> tuple[str, ...]:
        """What a caller passes per sample."""
        return ("time_s", "x_m", "tau0_K") if self.law == "line" else ("time_s", "x_m")

    def alpha(self, t: float, tau0: float) -> float:
        """α′ (m²/s) at time ``t`` (table law) or rise ``tau0`` (line law)."""
        if self.law == "line":
            return max(self.a0 + self.a1 * tau0, ALPHA_FLOOR)
        lt, xs, ys = math.log(t), self.log_t, self.log_alpha
        if lt <= xs[0]:
            return math.exp(ys[0])
        if lt >= xs[-1]:
            return math.exp(ys[-1])
        j = 0
        while lt > xs[j + 1]:
            j += 1
        slope = (ys[j + 1] - ys[j]) / (xs[j + 1] - xs[j])
        return math.exp(ys[j] + slope * (lt - xs[j]))

    def step(self, t: float, x: float, tau0: float = 0.0) -> tuple[int, float]:
        """``(0, E in µm)``, or ``(FAULT_READING, 0.0)`` for readings the law cannot use."""
        if not (math.isfinite(t) and math.isfinite(x) and x >= 0.0) or (self.law == "line" and not math.isfinite(tau0)):
            return FAULT_READING, 0.0
        if t <= 0.0:
            return 0, 0.0
        alpha = max(self.alpha(t, tau0), ALPHA_FLOOR)
        scale = 2.0 * math.sqrt(alpha * t)
        total = 0.0
        for u, w in zip(self.u, self.w):
            xi = x * u
            gamma = (self.c1 * math.exp(-self.lam * xi) + self.c2 * math.exp(self.lam * xi)) * math.erfc(
                (xi + self.x0) / scale
            )
            total = total + gamma * w
        return 0, 1e6 * self.expansion * x * total

    def replay(self, time, x, tau0=None) -> tuple[np.ndarray, np.ndarray]:
        """Codes and errors (µm, NaN under a fault) of every sample."""
        n = len(time)
        tau0 = np.zeros(n) if tau0 is None else np.asarray(tau0, dtype=float)
        codes, values = np.zeros(n, dtype=int), np.empty(n)
        for k in range(n):
            codes[k], values[k] = self.step(float(time[k]), float(x[k]), float(tau0[k]))
        values[codes != 0] = np.nan
        return codes, values

    def to_json(self) -> dict[str, Any]:
        """The law's numbers for any runtime (``groupfit-ballscrew-runtime/1``)."""
        return {
            "format": "groupfit-ballscrew-runtime/1",
            "readings": list(self.readings),
            "source": self.source,
            "alpha_law": self.law,
            "C1_K": self.c1,
            "C2_K": self.c2,
            "lambda_1_m": self.lam,
            "source_offset_m": self.x0,
            "expansion_1_K": self.expansion,
            "alpha_floor_m2_s": ALPHA_FLOOR,
            "line": {"a0_m2_s": self.a0, "a1_m2_sK": self.a1, "reference_x_m": self.reference_x_m},
            "table": {"ln_t_s": list(self.log_t), "ln_alpha_m2_s": list(self.log_alpha)}
            if self.law == "table"
            else None,
            "quadrature": {"u": list(self.u), "w": list(self.w)},
            "steps": [
                "fault -1 unless time_s and x_m are finite, x_m >= 0 (and tau0_K finite for the line law)",
                "E = 0 when time_s <= 0",
                "alpha = exp(ln_alpha interpolated linearly in ln t, held at the ends) or max(a0 + a1*tau0, floor)",
                "alpha = max(alpha, floor); s = 2*sqrt(alpha*t)",
                "for k in order: xi = x*u[k]; sum += (C1*exp(-lambda*xi) + C2*exp(lambda*xi))*erfc((xi+x0)/s)*w[k]",
                "E_um = 1e6*expansion*x*sum",
            ],
        }


__all__ = ["FAULT_READING", "ScrewLaw", "choose_source"]
