"""Which runs of a study can fit their breaks, and the refusal of a study that mostly cannot."""

from __future__ import annotations

from groupfit.errors import InputError
from groupfit.grouping import Constraints
from groupfit.search.exact import estimate_exact_cost, format_seconds
from groupfit.sweep.config import RunSpec, Study


def infeasible_reason(run: RunSpec, n_samples: int) -> str | None:
    """Why a run cannot fit its p breaks (the constraints of its n, c and inputs), or None when it can."""
    model, sensors = run.spec["model"], run.spec["sensors"]
    n_inputs = len(sensors["names"]) if "names" in sensors else int(sensors["k"])
    n_coef = n_inputs + int(model["intercept"])
    constraints = Constraints.for_model(n_samples, model["n"], model["c"], n_coef)
    largest = constraints.max_breaks()
    if model["p"] <= largest:
        return None
    return (
        f"p = {model['p']} with n = {model['n']}, c = {model['c']:g}, M = {n_coef} on {run.dataset} "
        f"(N = {n_samples}): at most p = {largest} fits"
    )


def feasibility(study: Study) -> tuple[list[RunSpec], list[tuple[RunSpec, str]]]:
    """The study's runs that can fit their breaks, and those that cannot with the reason."""
    sizes = {str(d.path): d.n_samples for d in study.datasets}
    feasible, infeasible = [], []
    for run in study.runs:
        reason = infeasible_reason(run, sizes[run.path])
        if reason is None:
            feasible.append(run)
        else:
            infeasible.append((run, reason))
    return feasible, infeasible


def check_feasible(study: Study, label: str) -> tuple[list[RunSpec], list[tuple[RunSpec, str]]]:
    """:func:`feasibility`, refusing a study none of whose runs, or fewer than half, can fit their breaks."""
    feasible, infeasible = feasibility(study)
    total = len(study.runs)
    if not feasible:
        raise InputError(
            f"{label}: none of the {total} runs can fit its breaks ({infeasible[0][1]}); "
            "lower p, n or c in [grid], or use fewer sensors"
        )
    if len(infeasible) > len(feasible):
        raise InputError(
            f"{label}: {len(infeasible)} of the {total} runs cannot fit their breaks (first: {infeasible[0][1]}); "
            "narrow [grid] to the runs that can (a study mostly of failures is refused)"
        )
    return feasible, infeasible


def check_exact_time(study: Study, runs: list[RunSpec], label: str, *, budget_s: float | None, workers: int) -> float:
    """The estimated time of the study's exact searches spread over ``workers``; refused over ``budget_s``.

    Each exact run costs what :func:`groupfit.search.exact.estimate_exact_cost` says of its N, M, objective
    and p (GA runs are not estimated). None: no budget (``--no-budget``).
    """
    sizes = {str(d.path): d.n_samples for d in study.datasets}
    seconds = 0.0
    for run in runs:
        model, sensors = run.spec["model"], run.spec["sensors"]
        if run.spec["search"]["method"] != "exact":
            continue
        n_coef = (len(sensors["names"]) if "names" in sensors else int(sensors["k"])) + int(model["intercept"])
        seconds += estimate_exact_cost(sizes[run.path], n_coef, model["objective"], model["p"]).seconds
    wall = seconds / max(workers, 1)
    if budget_s is not None and wall > budget_s:
        raise InputError(
            f"{label}: the exact searches of the study would take about {format_seconds(wall)} on {workers} "
            f"worker(s), over the budget of {format_seconds(budget_s)}: narrow [grid], add workers, or --no-budget"
        )
    return wall


__all__ = ["check_exact_time", "check_feasible", "feasibility", "infeasible_reason"]
