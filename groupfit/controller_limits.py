"""What a controller can hold: the ranges of the integer types the exports declare, and the words a
Structured Text name cannot be.

The C export declares its counters ``long`` (at least 32 bits by the C
standard; ``int`` may be 16); the Structured Text export declares ``INT``
(16 bits) where every value fits, else ``DINT`` (32 bits). A number no 32-bit
counter holds is refused by the model validator, naming the limit.
"""

from __future__ import annotations

import re

from groupfit.errors import InputError

INT_MAX = 2**15 - 1
"""Largest IEC 61131-3 ``INT`` (16 bits)."""
DINT_MAX = 2**31 - 1
"""Largest IEC 61131-3 ``DINT`` and the least C ``long`` (32 bits)."""
MAX_HOLD_SAMPLES = DINT_MAX - 1
"""Largest fault hold in samples a model file may hold: the controllers count to hold + 1 in a 32-bit counter."""

ST_RESERVED = frozenset(
    """
    ABS ACOS ACTION ADD AND ANY ANY_BIT ANY_DATE ANY_DERIVED ANY_ELEMENTARY ANY_INT ANY_MAGNITUDE ANY_NUM
    ANY_REAL ANY_STRING ARRAY ASIN AT ATAN BOOL BY BYTE CASE CONFIGURATION CONSTANT COS CTD CTU CTUD DATE
    DATE_AND_TIME DINT DIV DO DT DWORD ELSE ELSIF END_ACTION END_CASE END_CONFIGURATION END_FOR
    END_FUNCTION END_FUNCTION_BLOCK END_IF END_PROGRAM END_REPEAT END_RESOURCE END_STEP END_STRUCT
    END_TRANSITION END_TYPE END_VAR END_WHILE EQ EXIT EXP EXPT F_EDGE F_TRIG FALSE FOR FROM FUNCTION
    FUNCTION_BLOCK GE GT IF INITIAL_STEP INT INTERVAL LE LEN LIMIT LINT LN LOG LREAL LT LWORD MAX MIN MOD
    MOVE MUL MUX NE NON_RETAIN NOT OF ON OR PROGRAM R_EDGE R_TRIG READ_ONLY READ_WRITE REAL REPEAT RESOURCE
    RETAIN RETURN ROL ROR RS SEL SHL SHR SIN SINT SQRT SR STEP STRING STRUCT SUB TAN TASK THEN TIME TO TOD
    TON TOF TP TRANSITION TRUE TRUNC TYPE UDINT UINT ULINT UNTIL USINT VAR VAR_ACCESS VAR_CONFIG
    VAR_EXTERNAL VAR_GLOBAL VAR_IN_OUT VAR_INPUT VAR_OUTPUT VAR_TEMP WHILE WITH WORD WSTRING XOR
    """.split()
)
"""IEC 61131-3 keywords, elementary types and standard functions and blocks (case-insensitive there)."""


def st_integer_type(largest: int, what: str) -> str:
    """``INT`` when ``largest`` (≥ 0) fits 16 bits, else ``DINT``; one line naming the limit beyond 32 bits."""
    if largest <= INT_MAX:
        return "INT"
    if largest <= DINT_MAX:
        return "DINT"
    raise InputError(f"{what} = {largest}: more than a DINT holds ({DINT_MAX}); no controller counter can keep it")


ELEMENTARY_TYPES = (
    "BOOL BYTE WORD DWORD LWORD SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL TIME DATE TOD DT STRING WSTRING"
).split()
CONVERSION = re.compile(rf"^(?:(?:{'|'.join(ELEMENTARY_TYPES)}|BCD)_)?TO_(?:{'|'.join(ELEMENTARY_TYPES)}|BCD)$")
"""IEC 61131-3's type conversions (``TO_REAL``, ``LREAL_TO_REAL``, ``DINT_TO_BCD``): standard functions, which the
block itself calls."""

IDENTIFIER = re.compile(r"^(?!.*__)(?!.*_$)[A-Za-z_][A-Za-z0-9_]{0,63}$")
"""A Structured Text name (IEC 61131-3): letters, digits and single '_', a letter or '_' first, no '_' last, at
most 64 characters."""


def check_st_name(name: str, *, used: frozenset[str] = frozenset()) -> None:
    """Refuse a Structured Text name that is not an identifier, a reserved word or one of the block's own
    names (``used``)."""
    if not IDENTIFIER.match(name):
        raise InputError(
            f"block name {name!r}: use letters, digits and single '_' (a letter or '_' first, no '_' last, at most "
            "64 characters: an IEC 61131-3 name); choose another --name"
        )
    if name.upper() in ST_RESERVED or CONVERSION.match(name.upper()):
        raise InputError(f"block name {name!r}: a reserved word of Structured Text; choose another --name")
    if name.upper() in {u.upper() for u in used}:
        raise InputError(f"block name {name!r}: a name the block itself declares; choose another --name")


__all__ = ["DINT_MAX", "INT_MAX", "MAX_HOLD_SAMPLES", "ST_RESERVED", "check_st_name", "st_integer_type"]
