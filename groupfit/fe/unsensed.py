"""An unsensed, slow part of the machine structure as a lumped first-order lag.

A machine has heavy castings that no sensor watches: the bed under the
headstock, a column, an oil tank built into the base. Such a part warms with
its own, long time constant and its expansion moves the spindle relative to
the work, yet none of the temperature columns shows it. The part is one
lumped heat capacity ``C`` with a thermal resistance ``R`` to the ambient,
heated by a known share of the machine's heat ``P(t)``:

    C dθ/dt = s·P(t) − θ/R,        τ = R·C,

and its expansion adds ``k·θ`` to the thermal error. Writing ``y`` for the
heat "seen" by the part, ``τ dy/dt = P(t) − y`` with ``y(0) = 0``, the error
term is ``gain_um_per_W · y``, ``gain_um_per_W = k·s·R``; at steady state it is
``gain_um_per_W · P``. For a step of heat ``P`` at t = 0 the term is
``gain_um_per_W · P · (1 − e^{−t/τ})``: 63.2 % of its final value at t = τ.

``P(t)`` is either the bearing heat of the spindle (``heat = "bearings"``,
e.g. lubricating oil carrying bearing heat to a tank in the column) or the
heat that flows from the housing through the mounting face into the bed
(``heat = "bed"``, the bed casting under the headstock). The coupling is one
way: the housing model keeps its bed at the ambient temperature, so the part
is a correction to the error only (its own warming is small next to the
housing's, and its influence on the mounting-face heat flow is neglected).

The recursion is the exact solution for a heat input held constant over each
time step, ``y ← a·y + (1 − a)·P`` with ``a = e^{−Δt/τ}``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

HEAT_INPUTS = ("bearings", "bed")


@dataclass(frozen=True)
class UnsensedPart:
    """Parameters of the unsensed part (config table ``[unsensed_part]``).

    Parameters
    ----------
    tau_s
        Time constant ``τ = R·C`` of the part (s).
    gain_um_per_W
        Error per watt of steady heat input (µm/W); the sign says whether the
        part's expansion raises (positive) or lowers the error.
    heat
        ``"bearings"`` (front + rear bearing heat at the current speed) or
        ``"bed"`` (heat flowing from the housing into the bed).
    """

    tau_s: float
    gain_um_per_W: float
    heat: str = "bearings"


class FirstOrderLag:
    """The state ``y`` (W) of the part, stepped with a fixed time step ``dt``."""

    def __init__(self, part: UnsensedPart, dt: float):
        self.part = part
        self.decay = math.exp(-dt / part.tau_s)
        self.state_W = 0.0

    def step(self, heat_W: float) -> None:
        """Advance one time step with ``heat_W`` held during the step."""
        self.state_W = self.decay * self.state_W + (1.0 - self.decay) * heat_W

    @property
    def error_um(self) -> float:
        return self.part.gain_um_per_W * self.state_W
