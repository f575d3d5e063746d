"""``groupfit sweep``: run every combination of a study, locally or on a Dask cluster."""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

from tqdm import tqdm

from groupfit.commands import common
from groupfit.data_options import parse_temp_range
from groupfit.errors import InputError
from groupfit.outputs import current_plan
from groupfit.sweep.config import read_study
from groupfit.sweep.executors import DaskExecutor, LocalExecutor
from groupfit.sweep.feasibility import check_exact_time, check_feasible, check_table_memory
from groupfit.sweep.report import REPORT_HEADERS, write_report
from groupfit.sweep.store import StudyStore
from groupfit.sweep.study import run_study

MAX_FAILURES_SHOWN = 5


def add_parser(verbs) -> None:
    sweep = verbs.add_parser("sweep")
    sweep.add_argument("config", metavar="CONFIG", help="TOML sweep study (see docs/sweep.md)")
    sweep.add_argument("--workers", type=int, metavar="K", help="local worker processes (default: all cores)")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="run on a Dask cluster, e.g. tcp://host:8786")
    sweep.add_argument(
        "--connect-timeout",
        type=float,
        default=10.0,
        metavar="SECONDS",
        help="seconds to wait for the Dask scheduler (default 10)",
    )
    sweep.add_argument("--db", metavar="FILE", help="study database (SQLite; default [study] db or CONFIG-stem.sqlite)")
    common.add_out_option(sweep, "write a summary table and figures to DIR", aliases=("--report",))
    common.add_json_option(sweep, "counts and the database path")
    common.add_quiet_option(sweep)
    common.add_budget_option(sweep)
    common.add_clock_options(sweep)  # in place of the study's [data] period_tolerance and resample_s
    common.add_glitch_option(sweep)  # in place of [data] keep_glitches
    sweep.add_argument(
        "--range-temp",
        metavar="LOW,HIGH",
        help="plausible temperature readings in °C, in place of [data] temp_range (default -50,500; write "
        "--range-temp=-60,250 for a negative LOW); a reading outside is refused",
    )
    sweep.set_defaults(handler=run_sweep)


MAX_CONNECT_TIMEOUT_S = 3600.0
"""The longest wait for a Dask scheduler --connect-timeout takes (an hour)."""


def check_executor_options(args: argparse.Namespace) -> None:
    """Refuse before any work --workers below 1, an empty --scheduler and a --connect-timeout out of range."""
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers {args.workers}: give 1 or more worker processes")
    if args.scheduler is not None and not args.scheduler.strip():
        raise InputError("--scheduler '': an empty address; name the Dask scheduler (tcp://host:8786) or leave it out")
    if not (math.isfinite(args.connect_timeout) and 0 < args.connect_timeout <= MAX_CONNECT_TIMEOUT_S):
        raise InputError(
            f"--connect-timeout {args.connect_timeout:g}: give the seconds to wait for the scheduler, > 0 and at "
            f"most {MAX_CONNECT_TIMEOUT_S:g}"
        )


def make_executor(args: argparse.Namespace, out):
    """The Dask cluster --scheduler names, else local processes (a note when more are asked than cores)."""
    if args.scheduler:
        return DaskExecutor(args.scheduler, connect_timeout=args.connect_timeout)
    cores = os.cpu_count() or 1
    if args.workers is not None and args.workers > cores:
        print(
            f"note    --workers {args.workers} on {cores} core(s): the processes share them, so runs take longer "
            "each and the sweep no less time",
            file=out,
        )
    return LocalExecutor(args.workers)


def run_sweep(args: argparse.Namespace) -> int:
    given = {"period_tolerance": args.period_tolerance, "resample_s": args.resample}
    given["keep_glitches"] = args.keep_glitches
    temp_range = parse_temp_range(args.range_temp)
    given["temp_range"] = None if temp_range is None else list(temp_range)
    study = read_study(args.config, given)
    if not study.runs:
        raise InputError(f"{args.config}: the study has no runs")
    feasible, infeasible = check_feasible(study, args.config)
    check_executor_options(args)
    if args.db == "-":
        raise InputError("--db -: the study's database is a file the sweep reads back and resumes; name one")
    db = Path(args.db) if args.db else (study.db or Path.cwd() / f"{Path(args.config).stem}.sqlite")
    report_dir = common.plan_outputs(
        args,
        args.config,
        [d.path for d in study.datasets],
        folder=args.out,
        files=("runs.csv", "summary.csv", "summary.md"),
        headers=REPORT_HEADERS,
    )
    current_plan().file(db, "--db")
    if not args.scheduler:  # a cluster's size is known only once connected
        budget = None if args.no_budget else common.EXACT_BUDGET_SECONDS
        check_exact_time(study, feasible, args.config, budget_s=budget, workers=args.workers or os.cpu_count() or 1)
    if not args.no_budget:  # on a cluster, what one worker holds
        workers = 1 if args.scheduler else args.workers or os.cpu_count() or 1
        check_table_memory(study, feasible, args.config, budget_bytes=common.EXACT_BUDGET_BYTES, workers=workers)
    out = common.report_stream(args)
    executor = make_executor(args, out)
    try:
        with StudyStore(db) as store:
            print(
                f"study {study.name} ({args.config}): {len(study.runs)} runs on {executor.describe()}",
                file=out,
                flush=True,
            )
            common.print_notes(study.datasets, out)
            if infeasible:
                print(
                    f"  {len(feasible)} run(s) will fit; {len(infeasible)} cannot fit their breaks and will be "
                    f"recorded as failed (first: {infeasible[0][1]})",
                    file=out,
                    flush=True,
                )
            bar = tqdm(
                total=len(study.runs), desc="runs", unit="run", file=sys.stderr, disable=True if args.quiet else None
            )
            try:
                already = len(store.done_hashes(r.run_hash for r in study.runs))
                bar.update(already)
                outcome = run_study(study, store, executor, progress=bar.update)
            finally:
                bar.close()
            written = []
            if report_dir is not None:
                rows = store.rows([r.run_hash for r in study.runs])
                written = write_report(rows, report_dir, title=study.name)
    finally:
        executor.close()

    print(
        f"  done {outcome.done}, skipped {outcome.skipped} (done before), failed {outcome.failed}, "
        f"in {outcome.seconds:.1f} s",
        file=out,
    )
    if outcome.elsewhere:
        print(f"  {outcome.elsewhere} run(s) taken by another sweep on the same database", file=out)
    print(f"  database {outcome.db}", file=out)
    for run_hash, message in outcome.failures[:MAX_FAILURES_SHOWN]:
        print(f"  failed {run_hash[:12]}: {message}", file=out)
    if outcome.failed > MAX_FAILURES_SHOWN:
        print(
            f"  … and {outcome.failed - MAX_FAILURES_SHOWN} more failed runs (status 'failed' in the database)",
            file=out,
        )
    if written:
        common.commit_outputs()
        print("  report " + ", ".join(str(p) for p in written), file=out)
    json_path = common.write_json(
        args.json,
        {
            "db": str(outcome.db),
            "study": study.name,
            "config": str(args.config),
            "executor": executor.name,
            "total": outcome.total,
            "done": outcome.done,
            "skipped": outcome.skipped,
            "failed": outcome.failed,
            "elsewhere": outcome.elsewhere,
            "seconds": outcome.seconds,
            "failures": [{"run_hash": h, "error": m} for h, m in outcome.failures],
            "report": [str(p) for p in written],
        },
    )
    common.commit_outputs()
    if json_path is not None:
        print(f"  wrote {json_path}", file=out)
    return 0
