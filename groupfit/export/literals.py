"""Number literals that read back to exactly the value the Python rule uses.

Seventeen significant digits round-trip any IEEE double; nine round-trip any
IEEE single, so a table written with these literals holds, after the C or PLC
compiler has read it, the very numbers :class:`groupfit.runtime.SwitchingRule`
computes with.
"""

from __future__ import annotations

import math

import numpy as np

from groupfit.export.reading_units import TEMPERATURE_UNIT, conversion_note, is_temperature_reading


def double_literal(value: float) -> str:
    """A C / Structured Text literal of a double, exact on reading back."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"cannot write {value!r} as a literal")
    return "%.17e" % value


def single_literal(value: float) -> str:
    """A decimal literal (no suffix) of ``value`` rounded to IEEE single, exact on reading back."""
    single = np.float32(value)
    if not np.isfinite(single):
        raise ValueError(f"{value!r} does not fit a single-precision number")
    return "%.9e" % float(single)


def c_float_literal(value: float) -> str:
    """A C ``float`` literal (``f`` suffix) of ``value`` rounded to single precision."""
    return single_literal(value) + "f"


def integer_literal(value: int) -> str:
    return str(int(value))


def shortest_literal(value: float, *, single: bool) -> str:
    """The shortest decimal literal that reads back to ``value`` (as a double, or rounded to single).

    Always has a decimal point, as IEC 61131-3 real literals need
    (``1e-05`` becomes ``1.0e-05``). Shorter tables parse faster in tools that
    read Structured Text character by character.
    """
    if single:
        number = np.float32(value)
        if not np.isfinite(number):
            raise ValueError(f"{value!r} does not fit a single-precision number")
        text = (
            np.format_float_positional(number, unique=True, trim="0")
            if 1e-4 <= abs(number) < 1e7 or number == 0
            else np.format_float_scientific(number, unique=True, trim="0")
        )
    else:
        number = float(value)
        if not math.isfinite(number):
            raise ValueError(f"cannot write {value!r} as a literal")
        text = repr(number)
    mantissa, _, exponent = text.lower().partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    if mantissa.endswith("."):
        mantissa += "0"
    text = mantissa + (f"e{exponent}" if exponent else "")
    exact = np.float32(float(text)) == number if single else float(text) == number
    if not exact:  # never expected; the fixed-width forms are always exact
        return single_literal(value) if single else double_literal(value)
    return text


def reading_notes(tables, criterion_word: str) -> list[tuple[str, str, str, str]]:
    """What each reading is, for generated comments: ``(name, valid range, unit, note)`` in order."""
    notes_per_reading = []
    for r, name in enumerate(tables.raw_names):
        temperature = is_temperature_reading(tables, r)
        unit = f" {TEMPERATURE_UNIT}" if temperature else ""
        notes = [criterion_word] if r == tables.criterion_reading else []
        convert = conversion_note(name) if temperature else None
        notes += [convert] if convert else []
        fed = [d.name for d in tables.derived if d.reading == r]
        if fed:
            notes.append(("source of " if r >= tables.n_measured else "also the source of ") + ", ".join(fed))
        if r == getattr(tables, "reference_reading", -1):
            notes.append("reference: subtracted from every measured input")
        if r == getattr(tables, "dead_band_reading", -1):
            notes.append("dead band reference")
        if r == getattr(tables, "position_reading", -1):
            notes.append("axis position, mm; clamped to the travel")
        note = f"  ({'; '.join(notes)})" if notes else ""
        notes_per_reading.append((name, f"[{tables.valid_min[r]:g}, {tables.valid_max[r]:g}]", unit, note))
    return notes_per_reading


def reading_comments(tables, criterion_word: str, array: str, first_index: int, comment_text) -> list[str]:
    """One comment line a reading, ``array[index] = name  [low, high] unit  (notes)``, and a line on the units
    where sources are read; ``comment_text`` makes a name fit the comment, the caller adds the comment markers."""
    lines = [
        f"{array}[{r + first_index}] = {comment_text(name)}  {valid}{unit}{comment_text(note)}"
        for r, (name, valid, unit, note) in enumerate(reading_notes(tables, criterion_word))
    ]
    if tables.source_names:
        lines.append("(temperatures in degC; a source in the unit of its column in the modelling data)")
    return lines


def real_literal(value: float) -> str:
    """``GF_R(double, float)``: a C table entry of one real number (double and single literal)."""
    return f"GF_R({double_literal(value)}, {c_float_literal(value)})"


def c_comment_text(text: str) -> str:
    """Names as they may appear in a C comment: ASCII, no comment terminators."""
    cleaned = text.encode("ascii", "replace").decode("ascii")
    return cleaned.replace("*/", "* /").replace("/*", "/ *")


def st_comment_text(text: str) -> str:
    """Names as they may appear in a Structured Text comment: ASCII, no comment delimiters."""
    cleaned = text.encode("ascii", "replace").decode("ascii")
    return cleaned.replace("*)", "* )").replace("(*", "( *")
