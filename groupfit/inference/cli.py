"""Command-line options of the break intervals, shared by ``fit`` and ``compare``."""

from __future__ import annotations

import argparse

from groupfit.errors import InputError
from groupfit.inference import METHODS, BreakIntervalReport, break_intervals
from groupfit.search.base import DEFAULT_SEED

AUTO_BUDGET_S = 5.0
"""``--intervals auto`` skips a bootstrap projected to take longer than this."""


def add_interval_options(parser: argparse.ArgumentParser) -> None:
    """``--intervals``, ``--level``, ``--bootstrap``, ``--block``, ``--homoskedastic``."""
    parser.add_argument(
        "--intervals",
        choices=METHODS,
        default="auto",
        help="break confidence intervals: Bai (sse, n = 0), residual block bootstrap, or none "
        f"(default auto: Bai where it applies, else the bootstrap when it takes under {AUTO_BUDGET_S:.0f} s)",
    )
    parser.add_argument("--level", type=float, default=0.95, help="confidence level of the intervals (default 0.95)")
    parser.add_argument("--bootstrap", type=int, default=200, metavar="B", help="bootstrap refits (default 200)")
    parser.add_argument("--block", type=int, metavar="L", help="bootstrap block length in samples (default N^(1/3))")
    parser.add_argument(
        "--homoskedastic",
        action="store_true",
        help="Bai's interval with one Q and sigma over the run (strucchange het.reg = het.err = FALSE)",
    )


def check_block(args: argparse.Namespace, n_samples: int) -> None:
    """Refuse before any work a ``--block`` no shorter than the run (every replicate would be the run itself)."""
    if getattr(args, "block", None) is not None and not 1 <= args.block < n_samples:
        raise InputError(
            f"--block {args.block}: the bootstrap block must be 1 to {n_samples - 1} samples (the run has "
            f"N = {n_samples}); with L ≥ N every replicate is the run itself and the intervals have width zero"
        )


def intervals_from_args(args: argparse.Namespace, estimator, X, y, seed, progress=None) -> BreakIntervalReport:
    """The break intervals the options ask for, of a fitted grouped model."""
    return break_intervals(
        estimator,
        X,
        y,
        method=args.intervals,
        level=args.level,
        het=not args.homoskedastic,
        n_boot=args.bootstrap,
        block=args.block,
        seed=DEFAULT_SEED if seed is None else int(seed),
        budget_s=AUTO_BUDGET_S,
        progress=progress if progress is not None else False,
    )


def interval_settings(args: argparse.Namespace) -> dict:
    """The options as :func:`groupfit.inference.break_intervals` keywords (``compare``)."""
    return {
        "method": args.intervals,
        "level": args.level,
        "het": not args.homoskedastic,
        "n_boot": args.bootstrap,
        "block": args.block,
    }


def interval_notes(reports: dict) -> list[str]:
    """One line per distinct way the break intervals of ``compare`` were obtained (or not)."""
    groups: dict[str, list] = {}
    for p, report in reports.items():
        groups.setdefault(f"{100 * report.level:g} % break intervals: {report.detail}", []).append((p, report))
    lines = []
    for text, members in groups.items():
        ps = ", ".join(str(p) for p, _ in members)
        seconds = [r.seconds for _, r in members if r.seconds is not None]
        if seconds and not members[0][1].intervals:
            text += f" (p = {ps}; they would take about {sum(seconds):.0f} s)"
        elif seconds:
            text += f" (p = {ps}; {sum(seconds):.1f} s)"
        else:
            text += f" (p = {ps})"
        lines.append(text)
    return lines
