"""Which runs of a study can fit their breaks, and the refusal of a study that mostly cannot."""

from __future__ import annotations

from groupfit.errors import InputError
from groupfit.grouping import Constraints
from groupfit.objective import segment_table_bytes
from groupfit.search.exact import estimate_exact_cost, format_seconds
from groupfit.sweep.config import RunSpec, Study


def dataset_sizes(study: Study) -> dict[str, int]:
    """The samples of each of the study's datasets, by the path its runs name."""
    return {str(d.path): d.n_samples for d in study.datasets}


def n_coefficients(run: RunSpec) -> int:
    """The coefficients of one group of a run's model: its inputs and the intercept."""
    model, sensors = run.spec["model"], run.spec["sensors"]
    return (len(sensors["names"]) if "names" in sensors else int(sensors["k"])) + int(model["intercept"])


def infeasible_reason(run: RunSpec, n_samples: int) -> str | None:
    """Why a run cannot fit its p breaks (the constraints of its n, c and inputs), or None when it can."""
    model = run.spec["model"]
    n_coef = n_coefficients(run)
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
    sizes = dataset_sizes(study)
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
    sizes = dataset_sizes(study)
    seconds = 0.0
    for run in runs:
        model = run.spec["model"]
        if run.spec["search"]["method"] != "exact":
            continue
        seconds += estimate_exact_cost(sizes[run.path], n_coefficients(run), model["objective"], model["p"]).seconds
    wall = seconds / max(workers, 1)
    if budget_s is not None and wall > budget_s:
        raise InputError(
            f"{label}: the exact searches of the study would take about {format_seconds(wall)} on {workers} "
            f"worker(s), over the budget of {format_seconds(budget_s)}: narrow [grid], add workers, or --no-budget"
        )
    return wall


def check_table_memory(study: Study, runs: list[RunSpec], label: str, *, budget_bytes: float, workers: int) -> float:
    """The memory of the tables of segment sums the study's grouped runs (p ≥ 1) hold at once, ``workers`` at a
    time (the largest ones together); refused over ``budget_bytes``. A global run (p = 0) builds none."""
    sizes = dataset_sizes(study)
    tables = sorted(
        ((segment_table_bytes(sizes[run.path], n_coefficients(run)), run) for run in runs if run.spec["model"]["p"]),
        key=lambda item: item[0],
        reverse=True,
    )
    together = tables[: max(workers, 1)]
    peak = sum(size for size, _ in together)
    if peak > budget_bytes:
        size, run = together[0]
        at_once = f"{len(together)} at once on {workers} worker(s)" if len(together) > 1 else "one"
        raise InputError(
            f"{label}: the grouped runs' tables of segment sums would take about {peak / 1e9:.1f} GB ({at_once}; "
            f"the largest {size / 1e9:.1f} GB: {run.dataset}, N = {sizes[run.path]}, M = {n_coefficients(run)} "
            f"coefficients), over the budget of {budget_bytes / 1e9:g} GB: lower --workers, use fewer sensors or "
            "a thinned dataset, or --no-budget"
        )
    return peak


__all__ = [
    "check_exact_time",
    "check_feasible",
    "check_table_memory",
    "dataset_sizes",
    "feasibility",
    "infeasible_reason",
    "n_coefficients",
]
