"""What a run of many GA fits will take, projected from the first one: said, or refused over a budget."""

from __future__ import annotations

from groupfit.errors import InputError


def check_projection(p: int, first_s: float, *, pmax: int, asked: int, budget_s: float | None, estimate) -> None:
    """After the first GA fit (p = 1, ``first_s`` seconds), the projected time of p = 1…pmax; refused over
    ``budget_s``."""
    if p != 1:
        return
    projected = first_s * pmax * (pmax + 1) / 2
    capped = f" (the largest feasible p; --pmax {asked} asked)" if asked > pmax else ""
    line = f"grouped models p = 1…{pmax}{capped} by the GA: about {projected / 60:.0f} min"
    if budget_s is not None and projected > budget_s:
        raise InputError(
            f"{line}, over the budget of {budget_s / 60:.0f} min: lower --pmax, or --no-budget runs it anyway"
        )
    if estimate is not None and projected > 60:
        estimate(line)


__all__ = ["check_projection"]
