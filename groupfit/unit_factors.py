"""A unit given with a factor in a column's name: ``dZ [1/1000 mm]``, ``dZ [0.1 µm]``, ``T1 [°C/10]``.

Gauges and PLCs log integers in a fraction of a unit (thousandths of a millimetre, tenths of a degree) and say
so in the name. Such a name gives the unit and a factor; the factor is read as part of the unit, so that
``[1/1000 mm]`` is 1 µm and ``[0.1°C]`` a tenth of a degree, never the bare unit.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

NUMBER = r"\d+(?:[.,]\d+)?(?:[eE][-+]?\d+)?|[.,]\d+(?:[eE][-+]?\d+)?"
OPEN, CLOSE = r"[\[(（［]", r"[\])）］]"
UNIT = r"[^\d\s\])）］/*×x·.,][^\])）］/*×·]*?"
FACTORED_UNIT = re.compile(
    rf"{OPEN}\s*(?:(?P<num>{NUMBER})\s*/\s*(?P<den>{NUMBER})|(?P<mul>{NUMBER}))\s*[*×x·]?\s*(?P<unit>{UNIT})\s*"
    rf"{CLOSE}\s*$"
    rf"|{OPEN}\s*(?P<unit2>{UNIT})\s*(?P<op>[/*×·])\s*(?P<num2>{NUMBER})\s*{CLOSE}\s*$"
)
"""A bracketed unit with a number: ``[1/1000 mm]``, ``[0.001 mm]``, ``(10 nm)``, ``[µm/10]``, ``[°C*0.1]``."""


@dataclass(frozen=True)
class FactoredUnit:
    """The unit a name gives with a factor: ``factor`` of ``unit`` (``shown`` as written)."""

    factor: float
    unit: str
    shown: str


def _number(text: str) -> float:
    return float(text.replace(",", "."))


def factored_unit(name: object) -> FactoredUnit | None:
    """The unit and factor a column's name ends in (module docstring); None when it ends in no such bracket.

    The unit is returned as written (``mm``, ``°C``); whether it is a unit of length or temperature is the
    caller's to check. A factor of 0 reads as no factor (None).
    """
    match = FACTORED_UNIT.search(str(name)) if name is not None else None
    if match is None:
        return None
    if match.group("unit") is not None:
        unit = match.group("unit")
        if match.group("mul") is not None:
            factor = _number(match.group("mul"))
        else:
            denominator = _number(match.group("den"))
            factor = _number(match.group("num")) / denominator if denominator else 0.0
    else:
        unit, number = match.group("unit2"), _number(match.group("num2"))
        factor = number if match.group("op") != "/" else (1.0 / number if number else 0.0)
    if not factor or factor != factor:
        return None
    shown = match.group(0).strip()[1:-1].strip()
    return FactoredUnit(factor=factor, unit=unit.strip(), shown=shown)


__all__ = ["FactoredUnit", "factored_unit"]
