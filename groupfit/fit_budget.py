"""What the grouped fits will take: the GA fits of p = 1…pmax projected from the first one, and the memory of a
grouped model's table of segment sums; said, or refused over a budget."""

from __future__ import annotations

import time
from typing import Callable

from groupfit.errors import InputError
from groupfit.objective import segment_table_bytes


def check_projection(first_s: float, *, pmax: int, asked: int, budget_s: float | None, estimate) -> None:
    """The projected time of the GA fits p = 1…pmax from the first one's ``first_s`` (a fit's time taken to grow
    as p: the whole as p(p+1)/2 times the first); refused over ``budget_s``, said when over a minute."""
    projected = first_s * pmax * (pmax + 1) / 2
    capped = f" (the largest feasible p; --pmax {asked} asked)" if asked > pmax else ""
    line = f"grouped models p = 1…{pmax}{capped} by the GA: about {projected / 60:.0f} min"
    if budget_s is not None and projected > budget_s:
        raise InputError(
            f"{line}, over the budget of {budget_s / 60:.0f} min: lower --pmax, or --no-budget runs it anyway"
        )
    if estimate is not None and projected > 60:
        estimate(line)


def projecting(progress: Callable[[str, float], None], *, asked: int, budget_s: float | None, estimate):
    """A progress callback that passes every call on and projects the GA fits: the ``grouped`` stage calls it at
    0 when its clock starts and steps by 1/pmax after each fit, and fit p takes about p times the first. The
    projection from the first fit (timed from the stage's start) refuses a run over the budget without waiting
    for the second; the one from the second fit alone (the first may carry one-time work) checks it again, and
    the larger of the two is said (at 200 000 rows the fits took 73, 85, 253 and 320 s: the first fit
    projected 730 s, the second alone 425 s)."""
    state = {"start": None, "fits": 0, "last": None, "one_fit": 0.0}

    def call(stage: str, fraction: float) -> None:
        progress(stage, fraction)
        if stage != "grouped" or state["fits"] >= 2:
            return
        now = time.perf_counter()
        if fraction <= 0:
            state["start"] = now
            return
        state["fits"] += 1
        pmax = round(state["fits"] / fraction)
        since = state["start"] if state["fits"] == 1 else state["last"]
        state["last"] = now
        if since is not None:
            state["one_fit"] = max(state["one_fit"], (now - since) / state["fits"])
            check_projection(
                state["one_fit"],
                pmax=pmax,
                asked=asked,
                budget_s=budget_s,
                estimate=estimate if state["fits"] == 2 else None,
            )

    return call


def smallest_thinning(within: Callable[[int], bool], *, most: int) -> int:
    """The smallest power of two k >= 2 for which ``within(k)`` holds (one row in k kept), or the first one not
    below ``most`` when none before it does."""
    step = 2
    while step < most and not within(step):
        step *= 2
    return step


def segment_table_over(n_samples: int, n_coef: int, period: float, budget_bytes: float) -> str | None:
    """What a grouped model's table of segment sums on ``n_samples`` rows and ``n_coef`` coefficients would take,
    when over ``budget_bytes``, and how to bring it within: one line; None within the budget."""
    size = segment_table_bytes(n_samples, n_coef)
    if size <= budget_bytes:
        return None
    step = smallest_thinning(lambda k: segment_table_bytes(n_samples // k, n_coef) <= budget_bytes, most=n_samples)
    return (
        f"a grouped model (N = {n_samples} samples, M = {n_coef} coefficients) needs a table of segment sums of "
        f"{size / 1e9:.1f} GB, over the budget of {budget_bytes / 1e9:g} GB: keep one row in {step} "
        f"(--resample {step * period:g}) or choose fewer inputs (--select)"
    )


__all__ = ["check_projection", "projecting", "segment_table_over", "smallest_thinning"]
