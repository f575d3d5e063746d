"""Progress callbacks of the break searches, for the command line's bars."""

from __future__ import annotations

import math


def ga_reporter(progress, max_generations: int, stall_generations: int):
    """``progress("ga", fraction)`` per generation, the fraction of the run's likely length.

    The GA stops after ``stall_generations`` without improvement, usually long
    before ``max_generations``: the fraction is measured against the earlier
    of the two stops, so the bar keeps moving instead of waiting at
    generation / max_generations (and never goes back).
    """
    state = {"best": math.inf, "improved": 0, "shown": 0.0}

    def report(generation: int, best: float) -> None:
        if best < state["best"]:
            state["best"], state["improved"] = best, generation
        end = min(max_generations, state["improved"] + stall_generations)
        state["shown"] = max(state["shown"], min(1.0, generation / max(end, 1)))
        progress("ga", state["shown"])

    return report


def stage_reporter(progress, stage: str):
    """``progress(stage, fraction)`` as a callback of the fraction alone; None without ``progress``."""
    if progress is None:
        return None
    return lambda fraction: progress(stage, fraction)


__all__ = ["ga_reporter", "stage_reporter"]
