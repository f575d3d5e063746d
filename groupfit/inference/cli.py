"""Command-line options of the break intervals, shared by ``fit`` and ``compare``."""

from __future__ import annotations

import argparse

from groupfit.errors import InputError
from groupfit.inference import METHODS, BreakIntervalReport, break_intervals
from groupfit.search.base import DEFAULT_SEED

AUTO_BUDGET_S = 5.0
"""``--intervals auto`` skips a bootstrap projected to take longer than this."""
DEFAULT_LEVEL = 0.95
DEFAULT_REFITS = 200
BOOTSTRAP_ONLY = {"bootstrap": "--bootstrap", "block": "--block"}
"""The options only the bootstrap reads."""


def add_interval_options(parser: argparse.ArgumentParser) -> None:
    """``--intervals``, ``--level``, ``--bootstrap``, ``--block``, ``--homoskedastic``."""
    parser.add_argument(
        "--intervals",
        choices=METHODS,
        default="auto",
        help="break confidence intervals: Bai (sse, n = 0), residual block bootstrap, or none "
        f"(default auto: Bai where it applies, else the bootstrap when it takes under {AUTO_BUDGET_S:.0f} s)",
    )
    parser.add_argument("--level", type=float, help=f"confidence level of the intervals (default {DEFAULT_LEVEL:g})")
    parser.add_argument("--bootstrap", type=int, metavar="B", help=f"bootstrap refits (default {DEFAULT_REFITS})")
    parser.add_argument("--block", type=int, metavar="L", help="bootstrap block length in samples (default N^(1/3))")
    parser.add_argument(
        "--homoskedastic",
        action="store_true",
        help="Bai's interval with one Q and sigma over the run (strucchange het.reg = het.err = FALSE)",
    )


def check_block(args: argparse.Namespace, n_samples: int) -> None:
    """Refuse before any work an interval option the method would not read, and a ``--block`` no shorter than the
    run (every replicate would be the run itself)."""
    refuse_unused_interval_options(args)
    if getattr(args, "block", None) is not None and not 1 <= args.block < n_samples:
        raise InputError(
            f"--block {args.block}: the bootstrap block must be 1 to {n_samples - 1} samples (the run has "
            f"N = {n_samples}); with L ≥ N every replicate is the run itself and the intervals have width zero"
        )


def refuse_unused_interval_options(args: argparse.Namespace) -> None:
    """Refuse an interval option the method asked for would not read (``--intervals none --bootstrap 50``)."""
    if args.intervals == "none":
        given = [o for k, o in {**BOOTSTRAP_ONLY, "level": "--level"}.items() if getattr(args, k) is not None]
        if given or args.homoskedastic:
            option = given[0] if given else "--homoskedastic"
            raise InputError(f"{option}: --intervals none computes no interval; leave {option} out")
    if args.intervals == "bai":
        given = [o for k, o in BOOTSTRAP_ONLY.items() if getattr(args, k) is not None]
        if given:
            raise InputError(f"{given[0]}: an option of the bootstrap, and --intervals bai is not one; leave it out")
    if args.intervals == "bootstrap" and args.homoskedastic:
        raise InputError("--homoskedastic: an option of Bai's interval, not of the bootstrap; leave it out")


def intervals_from_args(args: argparse.Namespace, estimator, X, y, seed, progress=None) -> BreakIntervalReport:
    """The break intervals the options ask for, of a fitted grouped model."""
    return break_intervals(
        estimator,
        X,
        y,
        method=args.intervals,
        level=DEFAULT_LEVEL if args.level is None else args.level,
        het=not args.homoskedastic,
        n_boot=DEFAULT_REFITS if args.bootstrap is None else args.bootstrap,
        block=args.block,
        seed=DEFAULT_SEED if seed is None else int(seed),
        budget_s=AUTO_BUDGET_S,
        progress=progress if progress is not None else False,
    )


def interval_settings(args: argparse.Namespace) -> dict:
    """The options as :func:`groupfit.inference.break_intervals` keywords (``compare``)."""
    return {
        "method": args.intervals,
        "level": DEFAULT_LEVEL if args.level is None else args.level,
        "het": not args.homoskedastic,
        "n_boot": DEFAULT_REFITS if args.bootstrap is None else args.bootstrap,
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
