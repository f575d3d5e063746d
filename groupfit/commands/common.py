"""Pieces the verbs share: configuration and data loading, JSON output, progress bars."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from tqdm import tqdm

from groupfit.columns import aligned_inputs, shared_default_inputs
from groupfit.commands.option_values import resample_seconds
from groupfit.config import default_config_path, read_config
from groupfit.data import (
    ERROR_LIMIT_UM,
    PERIOD_TOLERANCE,
    TEMP_RANGE_C,
    Run,
    join_runs,
    load_run,
    load_runs,
    loading_notes,
)
from groupfit.data_options import (
    ERROR_HELP,
    add_encoding_option,
    encoding_name,
    parse_error_limit,
    parse_period_tolerance,
    parse_temp_range,
    split_names,
)
from groupfit.errors import InputError
from groupfit.export import write
from groupfit.fit_budget import smallest_thinning
from groupfit.io import atomic_write_text, refuse_repeated, to_json
from groupfit.io import check_output_dir as check_output_dir  # the verbs import it from here
from groupfit.outputs import commit_outputs as commit_outputs  # the verbs import it from here
from groupfit.outputs import current_plan
from groupfit.overlap import refuse_overlapping
from groupfit.resample import GAP_PERIODS
from groupfit.search.exact import estimate_exact_cost, format_seconds
from groupfit.settings import DataSettings, RunSettings

VALIDATION_RANGE = (
    "a reading outside is refused; in a --validate run a reading is scored as replay scores it: outside the run-time "
    "rule's valid range, held and then a sensor fault"
)
"""What becomes of a temperature outside ``--range-temp`` for a verb that also reads validation runs."""


def add_data_options(parser: argparse.ArgumentParser, *, range_temp: str | None = None) -> None:
    """--data, --time, --temps, --error, shared by the verbs that read a run; ``range_temp``: what becomes of a
    temperature outside ``--range-temp`` (:func:`add_range_options`, by default refused)."""
    parser.add_argument(
        "--data",
        nargs="+",
        metavar="RUN",
        help="the run (CSV, XLSX or Parquet with a header, one row per sample); several runs of a global model (p = 0)",
    )
    parser.add_argument("--time", metavar="COLUMN", help="time column in seconds (default time_s)")
    parser.add_argument("--temps", metavar="A,B,C", help="temperature input columns, comma separated")
    parser.add_argument("--error", metavar="COLUMN", help=ERROR_HELP)
    add_range_options(parser, **({"temp": range_temp} if range_temp else {}))
    add_clock_options(parser)
    add_encoding_option(parser)
    add_glitch_option(parser)


def add_range_options(
    parser: argparse.ArgumentParser, *, temp: str = "a reading outside is refused", refused: str = "refused"
) -> None:
    """``--range-temp LOW,HIGH`` and ``--range-error MAX``: the plausible readings of a run; what becomes of a
    temperature outside is ``temp``, an error beyond is ``refused``."""
    parser.add_argument(
        "--range-temp",
        metavar="LOW,HIGH",
        help=f"plausible temperature readings in °C (default {TEMP_RANGE_C[0]:g},{TEMP_RANGE_C[1]:g}; "
        f"write --range-temp=-60,250 for a negative LOW); {temp}",
    )
    parser.add_argument(
        "--range-error",
        metavar="MAX",
        help=f"largest plausible |thermal error| in µm (default 1e5); a larger value is {refused}",
    )


def range_options(args: argparse.Namespace) -> dict[str, Any]:
    """``temp_range`` and ``error_limit`` for :func:`groupfit.data.load_run` from ``--range-temp``/``--range-error``."""
    temp_range = parse_temp_range(getattr(args, "range_temp", None))
    error_limit = parse_error_limit(getattr(args, "range_error", None))
    return {
        "temp_range": TEMP_RANGE_C if temp_range is None else temp_range,
        "error_limit": ERROR_LIMIT_UM if error_limit is None else error_limit,
    }


def add_glitch_option(parser: argparse.ArgumentParser) -> None:
    """``--keep-glitches``: fit on the error's glitches too (:mod:`groupfit.glitches`)."""
    parser.add_argument(
        "--keep-glitches",
        action="store_true",
        default=None,
        help="keep error and temperature readings that leave their neighbours and come back (by default such a "
        "glitch of the error is left out as not measured, one of a temperature interpolated from its neighbours "
        "(kept as logged in a --validate run, as replay reads it), with a note naming its rows)",
    )


def add_clock_options(parser: argparse.ArgumentParser) -> None:
    """``--period-tolerance PERCENT`` and ``--resample SECONDS``: how a run's clock is read."""
    parser.add_argument(
        "--period-tolerance",
        metavar="PERCENT",
        help=f"largest deviation of a sampling interval from the period, in %% (default {100 * PERIOD_TOLERANCE:g}); "
        "a jittering clock within it is accepted with a note",
    )
    parser.add_argument(
        "--resample",
        type=resample_seconds,
        metavar="SECONDS",
        help="average the readings of every period of this many seconds (the period's centre as its time); "
        f"up to {GAP_PERIODS} empty periods in a row are interpolated, a longer gap splits the log into runs",
    )


def clock_options(args: argparse.Namespace, data: DataSettings | None = None) -> dict[str, Any]:
    """``period_tolerance`` and ``resample`` for :func:`groupfit.data.load_run`: the flags, else ``[data]``."""
    options = configured_clock(data or DataSettings())
    tolerance = parse_period_tolerance(getattr(args, "period_tolerance", None))
    if tolerance is not None:
        options["period_tolerance"] = tolerance
    if getattr(args, "resample", None) is not None:
        options["resample"] = args.resample
    if getattr(args, "encoding", None) is not None:
        options["encoding"] = encoding_name(args.encoding)
    return options


def configured_clock(data: DataSettings) -> dict[str, Any]:
    """``period_tolerance`` and ``resample`` for :func:`groupfit.data.load_run` from the configuration's ``[data]``."""
    tolerance = parse_period_tolerance(data.period_tolerance)
    clock = {"period_tolerance": PERIOD_TOLERANCE if tolerance is None else tolerance, "resample": data.resample_s}
    return clock if data.encoding is None else {**clock, "encoding": data.encoding}


def print_notes(runs, stream=None) -> None:
    """Print what loading did to each run, one ``note`` line each (:func:`groupfit.data.loading_notes`)."""
    for note in loading_notes(runs):
        print(f"note     {note}", file=stream or sys.stdout)


def add_run_options(parser: argparse.ArgumentParser, *, range_temp: str | None = None) -> None:
    """CONFIG (a TOML run configuration, default configs/default.toml) and the data options."""
    parser.add_argument(
        "config", nargs="?", metavar="CONFIG", help="TOML run configuration (default configs/default.toml)"
    )
    add_data_options(parser, range_temp=range_temp)


def add_model_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL", help="model file written by groupfit fit or groupfit diagnose")


def add_model_run_options(parser: argparse.ArgumentParser, help: str, *, several: bool = False) -> None:
    """``--data RUN`` (required) and ``--time COLUMN`` of a verb that reads a run against a model."""
    parser.add_argument("--data", required=True, nargs="+" if several else None, metavar="RUN", help=help)
    parser.add_argument(
        "--time",
        metavar="COLUMN",
        help="time column in seconds (default: the one the model was fitted with, else time_s)",
    )


def add_source_option(parser: argparse.ArgumentParser) -> None:
    """``--source NAME``: the heat source of a ball-screw model."""
    parser.add_argument("--source", metavar="NAME", help="ball-screw model: the heat source (default: its only one)")


def add_out_option(
    parser: argparse.ArgumentParser,
    help: str,
    *,
    metavar: str = "DIR",
    default: str | None = None,
    required: bool = False,
    aliases: tuple[str, ...] = ("-o", "--output"),
) -> None:
    """``--out``: where a verb writes its files; the older spellings (``-o``, ``--output``, ``--report``) stay
    hidden aliases."""
    shown = f"{help} (default {default})" if default else help
    parser.add_argument("--out", dest="out", metavar=metavar, default=default, help=shown)
    if aliases:
        parser.add_argument(*aliases, dest="out", metavar=metavar, help=argparse.SUPPRESS)
    if required:
        parser.set_defaults(out_required=True)
    add_force_option(parser)


def add_force_option(parser: argparse.ArgumentParser) -> None:
    """``--force``: replace an existing file that is not an earlier output of the same kind."""
    parser.add_argument(
        "--force",
        action="store_true",
        help="replace an existing data, model or other file named as an output that is not an earlier output of "
        "the same kind (never one the command reads)",
    )


def out_option(args: argparse.Namespace) -> str:
    """How a refusal names the output folder: ``--out`` when given on the command line (or when the verb
    names no run configuration), else the configuration's ``[output] dir`` it came from."""
    if getattr(args, "out", None) is not None or not vars(args).get("config"):
        return "--out"
    return f"[output] dir of {args.config}"


def plan_outputs(
    args: argparse.Namespace,
    *inputs,
    folder: str | Path | None = None,
    files=(),
    option: str | None = None,
    json_model: str | None = None,
    headers: dict[str, str] | None = None,
) -> Path | None:
    """Declare what a verb reads and writes, and check every output before any work (one line when refused).

    ``inputs`` are the files the verb reads (paths or lists of paths; None
    skipped); the outputs are ``--json`` and the files ``files`` in ``folder``
    (``option`` names it, by default :func:`out_option`; ``json_model``: the
    format of the model file the ``--json`` is, e.g. ``groupfit-model/``; ``headers``: how the header lines of
    the tables among ``files`` start, checked now against tables of those names). An
    output that is an input, an existing data file without ``--force``, or an
    empty path is refused
    (:class:`groupfit.outputs.OutputPlan`). Returns the folder (None when none).
    """
    plan = current_plan(force=getattr(args, "force", False)).read(*inputs)
    plan.file(getattr(args, "json", None), "--json", model=json_model or None, json=True)
    return plan.folder(folder, option or out_option(args), files, headers)


def add_register_options(
    parser: argparse.ArgumentParser, resolution_help: str, *, resolution_default: float | None = None, target: str = ""
) -> None:
    """``--resolution-um UM`` and ``--counts-limit N``: an integer compensation register, µm per count and the
    largest magnitude it holds (``target``: the export target it serves, named at the start of the help)."""
    parser.add_argument(
        "--resolution-um", type=float, default=resolution_default, metavar="UM", help=f"{target}{resolution_help}"
    )
    parser.add_argument(
        "--counts-limit",
        type=int,
        metavar="N",
        help=f"{target}largest magnitude of the integer compensation register in counts (default 30000)",
    )


def add_json_option(parser: argparse.ArgumentParser, what: str = "the result") -> None:
    """``--json FILE``: the machine-readable result, ``-`` for stdout."""
    parser.add_argument("--json", metavar="FILE", help=f"write {what} as JSON ('-' for stdout)")


def add_quiet_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def settings_with_data_options(args: argparse.Namespace) -> tuple[str | Path | None, RunSettings]:
    """The run configuration's path (CONFIG, else configs/default.toml) and its settings with --data, --time,
    --temps, --error and the other data options."""
    config_path = args.config or default_config_path()
    settings = read_config(config_path)
    if args.data and getattr(args, "config", None) is None:
        # a run given on the command line does not inherit the default configuration's runs and columns:
        # its inputs are --temps, else its own sensor columns; it is validated only on --validate runs
        settings = settings.without_default_runs()
    data = {
        "path": args.data[0] if args.data and len(args.data) == 1 else args.data,
        "time": args.time,
        "temps": split_names(args.temps),
        "error": args.error,
        "temp_range": parse_temp_range(getattr(args, "range_temp", None)),
        "error_limit": parse_error_limit(getattr(args, "range_error", None)),
        "period_tolerance": getattr(args, "period_tolerance", None),
        "resample_s": getattr(args, "resample", None),
        "ambient": getattr(args, "ambient", None),
        "keep_glitches": getattr(args, "keep_glitches", None),
        "encoding": encoding_name(args.encoding) if getattr(args, "encoding", None) else None,
    }
    return config_path, settings.given(data=data)


def load_configured_run(data: DataSettings, path: str | None = None, **options) -> Run:
    """Load the run named by ``path`` (default: the configuration's data path)."""
    runs = load_configured_runs(data, path, **options)
    if len(runs) > 1 and not isinstance(path or data.path, (list, tuple)):
        return load_run(path or data.path, **_load_options(data, options))  # names the gap
    return join_runs(runs)


def load_configured_runs(data: DataSettings, path: str | None = None, **options) -> list[Run]:
    """The runs named by ``path`` (default: the configuration's data path), a log split at its gaps by
    ``--resample`` giving one run per part; every run's inputs in the first's order (matched by name)."""
    paths = (path,) if path else data.paths
    if not paths:
        raise InputError("no data given: pass --data CSV or set [data] path in the configuration")
    refuse_repeated(paths, "as data")
    options = _load_options(data, options)
    runs = [run for p in paths for run in load_runs(p, **options)]
    if len(paths) > 1:
        runs = aligned_inputs(runs if data.temps is not None else shared_default_inputs(runs))
        refuse_overlapping(runs)
    return runs


def _load_options(data: DataSettings, options: dict) -> dict:
    options = dict(options)
    options.setdefault("temp_range", TEMP_RANGE_C if data.temp_range is None else data.temp_range)
    options.setdefault("error_limit", ERROR_LIMIT_UM if data.error_limit is None else data.error_limit)
    for key, value in configured_clock(data).items():
        options.setdefault(key, value)
    options.update(temps=list(data.temps) if data.temps is not None else None, time=data.time, error=data.error)
    if data.ambient is not None:
        options.setdefault("ambient", data.ambient)
    if options.get("missing_error"):  # a run that may hold unmeasured rows: its glitches become such rows
        options.setdefault("drop_glitches", not data.keep_glitches)
    return options


def write_json(target: str | None, obj: Any) -> Path | None:
    """Write a JSON result to a file, or to stdout for '-'; return the file written (None for stdout or none)."""
    if target is None:
        return None
    text = to_json(obj)
    if target == "-":
        sys.stdout.write(text)
        return None
    atomic_write_text(target, text)
    return Path(target)


def wrote_line(paths) -> str:
    """The files a verb wrote, comma separated (None entries left out)."""
    return ", ".join(str(p) for p in paths if p is not None)


def finish_outputs(args: argparse.Namespace, report: str, data: Any, figures) -> None:
    """Write ``data`` to ``--json``, commit the outputs, then print ``report`` and a ``wrote`` line naming the
    files written (none when nothing was)."""
    written = [*figures, write_json(args.json, data)]
    commit_outputs()
    lines = [report] + (["wrote    " + wrote_line(written)] if any(written) else [])
    print("\n".join(lines), file=report_stream(args))


def write_exports(args: argparse.Namespace, files: dict[str, str]) -> None:
    """Write the rendered ``files`` into ``--out`` (each checked first, :func:`plan_outputs`), commit them and
    print the ``wrote`` line."""
    written = write(files, plan_outputs(args, folder=args.out, files=files))
    commit_outputs()
    print("wrote " + ", ".join(str(p) for p in written))


def residual_line(result: dict[str, Any]) -> str:
    """The replay summary's residual line from ``rms_um``, ``max_um`` and ``scored_samples`` (or none)."""
    if result["rms_um"] is None and result.get("measured_samples"):
        return "residual none: no sample scored (every measured sample in sensor fault: the rule's safe output)"
    if result["rms_um"] is None:
        return "residual none (the run has no measured error: no error column, or no reading within its range)"
    return (
        f"residual RMS {result['rms_um']:.4g} µm, max |e| {result['max_um']:.4g} µm "
        f"over {result['scored_samples']} sample(s)"
    )


def report_stream(args: argparse.Namespace):
    """Where the human-readable report goes: stderr when JSON goes to stdout."""
    return sys.stderr if getattr(args, "json", None) == "-" else sys.stdout


EXACT_BUDGET_SECONDS = 15 * 60.0
"""Longest exact search a verb starts without --no-budget."""
EXACT_BUDGET_BYTES = 4e9
"""Largest estimated memory of an exact search a verb starts without --no-budget."""


def add_budget_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--no-budget",
        action="store_true",
        help="run an exact search even when its estimated time or memory exceeds the budget (15 min, 4 GB)",
    )


def check_exact_budget(args: argparse.Namespace, run: Run, n_coef: int, objective: str, pmax: int, what: str) -> None:
    """Refuse, before it starts, an exact search estimated to exceed the budget; one line saying what to do."""
    over = over_budget(args, run, n_coef, objective, pmax, what)
    if over is not None:
        cost, hints = over
        raise InputError(f"{run.source}: {cost}: use {', '.join(hints)}; --no-budget runs it anyway")


def over_budget(
    args: argparse.Namespace, run: Run, n_coef: int, objective: str, pmax: int, what: str
) -> tuple[str, list[str]] | None:
    """An exact search estimated to exceed the budget: what it would take, and what to do instead (the options
    the verb of ``args`` takes); None within the budget."""
    if getattr(args, "no_budget", False) or pmax == 0:  # p = 0: one least-squares fit, no search
        return None
    cost = estimate_exact_cost(run.n_samples, n_coef, objective, pmax)
    if _within_budget(cost):
        return None
    hints = []
    sse = estimate_exact_cost(run.n_samples, n_coef, "sse", pmax)
    if objective == "sae" and _within_budget(sse):
        setting = "--objective sse" if hasattr(args, "objective") else 'objective = "sse" in a configuration\'s [model]'
        hints.append(f"{setting} ({sse.describe()})")
    if hasattr(args, "search"):
        hints.append("--search ga --p P (the genetic algorithm)")
    else:
        for p in range(pmax - 1, 0, -1):  # the largest p whose exact path fits
            smaller = estimate_exact_cost(run.n_samples, n_coef, objective, p)
            if _within_budget(smaller):
                hints.append(f"--pmax {p} ({smaller.describe()})")
                break
    step = smallest_thinning(
        lambda k: _within_budget(estimate_exact_cost(run.n_samples // k, n_coef, objective, pmax)), most=64
    )
    hints.append(f"or keep one row in {step} of the run (--resample {step * run.period:g}: the mean of {step} rows)")
    return (
        f"{what} ({objective}, N = {run.n_samples} samples, M = {n_coef} coefficients) would take "
        f"{cost.describe()}, over the budget of {format_seconds(EXACT_BUDGET_SECONDS)} and "
        f"{EXACT_BUDGET_BYTES / 1e9:g} GB",
        hints,
    )


def _within_budget(cost) -> bool:
    return cost.seconds <= EXACT_BUDGET_SECONDS and cost.bytes <= EXACT_BUDGET_BYTES


class StageProgress:
    """A tqdm bar per named stage, driven by ``(stage, fraction)`` callbacks.

    When stderr is not a terminal (a log file, a CI job) there is no bar:
    one line per stage is logged instead each time the stage passes another
    ``LOG_STEP`` of its work, or every ``LOG_SECONDS`` while it is running;
    a stage done within ``QUIET_SECONDS`` logs nothing.
    """

    LOG_STEP = 0.1
    LOG_SECONDS = 5.0
    QUIET_SECONDS = 2.0

    def __init__(self, *, enabled: bool, stream=None):
        self.enabled = enabled
        self.stream = stream or sys.stderr
        self.bars: dict[str, tqdm] = {}
        self.logged: dict[str, tuple[float, float]] = {}
        self.stage_start: dict[str, float] = {}
        isatty = getattr(self.stream, "isatty", None)
        self.terminal = bool(isatty and isatty())

    def __call__(self, stage: str, fraction: float) -> None:
        if not self.enabled:
            return
        fraction = min(max(fraction, 0.0), 1.0)
        if not self.terminal:
            self._log(stage, fraction)
            return
        bar = self.bars.get(stage)
        if bar is None:
            bar = self.bars[stage] = tqdm(total=1000, desc=stage, leave=False, file=self.stream)
        bar.update(max(0, int(round(1000 * fraction)) - bar.n))

    def _log(self, stage: str, fraction: float) -> None:
        now = time.monotonic()
        first_seen = self.stage_start.setdefault(stage, now)
        if now - first_seen < self.QUIET_SECONDS:
            return  # a quick stage logs nothing
        last_fraction, last_time = self.logged.get(stage, (-1.0, first_seen))
        if last_fraction >= 1.0:
            return
        crossed = int(fraction / self.LOG_STEP) > int(max(last_fraction, 0.0) / self.LOG_STEP) or last_fraction < 0
        if crossed or (now - last_time >= self.LOG_SECONDS and fraction > last_fraction):
            elapsed = now - first_seen
            print(f"progress {stage}: {100 * fraction:.0f} % after {elapsed:.0f} s", file=self.stream, flush=True)
            self.logged[stage] = (fraction, now)

    def close(self) -> None:
        for bar in self.bars.values():
            bar.close()
        self.bars.clear()
