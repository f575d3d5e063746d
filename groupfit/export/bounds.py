"""Lines that keep a variable within its bounds, in C or Structured Text: the clamp and the rate-limited step.

Every export clamps its target to the compensation's bounds and moves its
output towards it by at most the rate limit a sample; the recalibration
bounds its state and its correction the same way (:mod:`groupfit.export.c_probe`,
:mod:`groupfit.export.st_probe`).
"""

from __future__ import annotations

from textwrap import indent

IF_BEYOND = {
    "c": "if ({name} {op} {bound}) {{\n    {name} = {bound};\n}}\n",
    "st": "IF {name} {op} {bound} THEN\n    {name} := {bound};\nEND_IF;\n",
}
"""Per language: ``name`` set to ``bound`` when it is beyond it (``op``: ``>`` or ``<``)."""
ASSIGN = {"c": "{name} = {value};\n", "st": "{name} := {value};\n"}


def clamp(language: str, name: str, low: str, high: str, margin: str = "") -> str:
    """``name`` held within ``[low, high]``: the upper bound first, as every target computes it."""
    beyond = IF_BEYOND[language]
    lines = beyond.format(name=name, op=">", bound=high) + beyond.format(name=name, op="<", bound=low)
    return indent(lines, margin)


def rate_limited_step(language: str, value: str, target: str, step: str, rate: str, margin: str = "") -> str:
    """``value`` moved towards ``target`` by at most ``rate`` (``step``: the variable of the move)."""
    assign = ASSIGN[language]
    move = indent(assign.format(name=step, value=f"{target} - {value}"), margin)
    limited = clamp(language, step, f"-{rate}", rate, margin)
    return move + limited + indent(assign.format(name=value, value=f"{value} + {step}"), margin)


__all__ = ["clamp", "rate_limited_step"]
