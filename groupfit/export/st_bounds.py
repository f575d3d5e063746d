"""Structured Text lines that keep a variable within its bounds: the clamp and the rate-limited step.

The function block clamps its target to ``COMP_MIN``/``COMP_MAX`` and moves
its output towards it by at most ``RATE_LIMIT`` a sample; the recalibration
bounds its state and its correction the same way (:mod:`groupfit.export.st_probe`).
"""

from __future__ import annotations

from textwrap import indent


def clamp(name: str, low: str, high: str, margin: str = "") -> str:
    """``name`` held within ``[low, high]``: the upper bound first, as every target computes it."""
    lines = (
        f"IF {name} > {high} THEN\n    {name} := {high};\nEND_IF;\n"
        f"IF {name} < {low} THEN\n    {name} := {low};\nEND_IF;\n"
    )
    return indent(lines, margin)


def rate_limited_step(value: str, target: str, step: str, rate: str, margin: str = "") -> str:
    """``value`` moved towards ``target`` by at most ``rate`` (``step``: the variable of the move)."""
    move = indent(f"{step} := {target} - {value};\n", margin)
    return move + clamp(step, f"-{rate}", rate, margin) + indent(f"{value} := {value} + {step};\n", margin)


__all__ = ["clamp", "rate_limited_step"]
