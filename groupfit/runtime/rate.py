"""The rate limit of the run-time routine: how far an output may move in one sample."""

from __future__ import annotations


def rate_limited(current, target, rate):
    """``current`` moved toward ``target`` by at most ``rate``, in the arithmetic of its arguments.

    The steps are those of the generated C and Structured Text, so that a
    single-precision replay rounds as the controller does.
    """
    delta = target - current
    if delta > rate:
        delta = rate
    if delta < -rate:
        delta = -rate
    return current + delta
