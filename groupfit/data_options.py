"""The command-line forms of the loader's options: ``--error`` (its help), ``--temps``, ``--range-temp``,
``--range-error``, ``--period-tolerance``, ``--encoding`` (and the same keys of a configuration's ``[data]`` table)."""

from __future__ import annotations

import argparse
import codecs
import csv

import numpy as np

from groupfit.errors import InputError

ERROR_HELP = (
    "thermal-error column in µm, or mm, nm by its name (default error_um); COLUMN*K reads it ×K µm per unit as "
    "logged (steps, counts, inches; K < 0 flips its sign); COLUMN-start (COLUMN*K-start or COLUMN-start*K) reads "
    "it less the run's first reading (a position or a sensor logged from another zero)"
)
MAX_PERIOD_TOLERANCE = 0.5
"""The widest ``--period-tolerance``: an interval half a period off the period is a missed or an extra
sample, which ``--resample`` handles."""


def parse_temp_range(text: str | None) -> tuple[float, float] | None:
    """``--range-temp=LOW,HIGH`` (°C; with ``=``, as LOW is usually negative)."""
    if text is None:
        return None
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError(f"--range-temp {text!r}: give LOW,HIGH in °C, e.g. --range-temp=-60,250") from None
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise InputError(f"--range-temp {text!r}: LOW and HIGH must be finite with LOW < HIGH")
    return low, high


def parse_error_limit(text: str | None) -> float | None:
    """``--range-error MAX`` (µm)."""
    return (
        None
        if text is None
        else positive_number(text, "--range-error", "the largest plausible |error| in µm, e.g. 1e5")
    )


def positive_number(text: str, option: str, asked: str) -> float:
    """``text`` as a finite number > 0; InputError naming ``option`` and what to give (``asked``) otherwise."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{option} {text!r}: give {asked}") from None
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{option} {text!r}: must be a finite number > 0")
    return value


def parse_period_tolerance(text: str | float | None) -> float | None:
    """``--period-tolerance PERCENT`` (or ``[data] period_tolerance``) as a fraction of the period."""
    if text is None:
        return None
    try:
        percent = float(str(text).strip().rstrip("%"))
    except ValueError:
        raise InputError(f"--period-tolerance {text!r}: give a percentage of the period, e.g. 2 or 5%") from None
    if not (np.isfinite(percent) and 0 <= percent < 100 * MAX_PERIOD_TOLERANCE):
        raise InputError(f"--period-tolerance {text!r}: must be a percentage in [0, {100 * MAX_PERIOD_TOLERANCE:g})")
    return percent / 100.0


def split_names(text: str | None) -> list[str] | None:
    """Split a comma-separated column list from the command line; a name in double quotes may hold a comma
    (``"Temp, °C (S/N 1)","Temp, °C (S/N 2)"``, as a HOBO logger names its columns)."""
    if text is None:
        return None
    try:
        fields = next(csv.reader([text], skipinitialspace=True), [])
    except csv.Error:
        fields = text.split(",")
    names = [t.strip() for t in fields if t.strip()]
    if not names:
        raise InputError(f"--temps {text!r}: give at least one column name, comma separated")
    return names


def encoding_name(text: str) -> str:
    """``--encoding NAME`` (``[data] encoding``): a text encoding Python knows, refused in one line otherwise."""
    try:
        codecs.lookup(text)
    except (LookupError, TypeError):
        raise InputError(
            f"--encoding {text!r}: not a text encoding (e.g. cp1250 for Central Europe, cp1254 for Turkey, "
            "iso-8859-7 for Greece, utf-8)"
        ) from None
    return text


ENCODING_HELP = (
    "the encoding the log's text was written in (cp1250, cp1254, iso-8859-7 …); by default it is told from the "
    "bytes: UTF-8/16/32, GBK, Big5, Shift-JIS, CP949, Windows-1251, Windows-1252"
)


def add_encoding_option(parser: argparse.ArgumentParser) -> None:
    """``--encoding NAME``: the encoding a text log was written in, when detection is not to decide."""
    parser.add_argument("--encoding", metavar="NAME", help=ENCODING_HELP)


__all__ = [
    "ENCODING_HELP",
    "ERROR_HELP",
    "add_encoding_option",
    "encoding_name",
    "parse_error_limit",
    "positive_number",
    "parse_period_tolerance",
    "parse_temp_range",
    "split_names",
]
