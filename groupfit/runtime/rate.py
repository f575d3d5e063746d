"""The bounds of the run-time routine: a value held within its limits, and how far an output may move in one
sample."""

from __future__ import annotations


def within(value, low, high):
    """``value`` held within ``[low, high]``, the upper bound first, as every export computes it."""
    if value > high:
        value = high
    if value < low:
        value = low
    return value


def rate_limited(current, target, rate):
    """``current`` moved toward ``target`` by at most ``rate``, in the arithmetic of its arguments.

    The steps are those of the generated C and Structured Text, so that a
    single-precision replay rounds as the controller does.
    """
    return current + within(target - current, -rate, rate)
