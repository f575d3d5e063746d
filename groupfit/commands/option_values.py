"""The values of the verbs' numeric options, checked as argparse reads them: one line naming the value when refused."""

from __future__ import annotations

import argparse

from groupfit.errors import InputError
from groupfit.model_checks import MAX_RIDGE_ALPHA
from groupfit.probe_intervals import parse_intervals


def resample_seconds(text: str) -> float:
    """--resample: a period in seconds > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give the period in seconds, e.g. 60") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: the period must be a number of seconds > 0")
    return value


def seed_value(text: str) -> int:
    """--seed: a whole number ≥ 0 (what numpy's generators take)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid seed: {text!r} (a whole number >= 0)") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"invalid seed: {text!r} (a whole number >= 0)")
    return value


def ridge_value(text: str) -> float | str:
    """--ridge: a penalty >= 0 or 'auto'."""
    if text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid penalty: {text!r} (a number >= 0 or 'auto')") from None
    if not (0 <= value <= MAX_RIDGE_ALPHA):
        raise argparse.ArgumentTypeError(f"invalid penalty: {text!r} (a number in [0, {MAX_RIDGE_ALPHA:g}] or 'auto')")
    return value


def check_intervals(text: str) -> list[float]:
    """--probe-every T,T,…: intervals with a unit (s, m, h; a bare number: seconds), each > 0."""
    try:
        return parse_intervals(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--probe-every: ")) from None


__all__ = ["check_intervals", "resample_seconds", "ridge_value", "seed_value"]
