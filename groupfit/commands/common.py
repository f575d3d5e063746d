"""Pieces the verbs share: configuration and data loading, JSON output, progress bars."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from tqdm import tqdm

from groupfit.config import override, read_config
from groupfit.data import Run, join_runs, load_run, split_names
from groupfit.errors import InputError
from groupfit.io import atomic_write_text, to_json


def add_data_options(parser: argparse.ArgumentParser) -> None:
    """--data, --time, --temps, --error, shared by the verbs that read a run."""
    parser.add_argument(
        "--data",
        nargs="+",
        metavar="RUN",
        help="the run (CSV, XLSX or Parquet with a header, one row per sample); several runs of a global model (p = 0)",
    )
    parser.add_argument("--time", metavar="COLUMN", help="time column in seconds (default time_s)")
    parser.add_argument("--temps", metavar="A,B,C", help="temperature input columns, comma separated")
    parser.add_argument("--error", metavar="COLUMN", help="thermal-error column in µm (default error_um)")


def add_run_options(parser: argparse.ArgumentParser) -> None:
    """CONFIG (a TOML run configuration, default configs/default.toml) and the data options."""
    parser.add_argument(
        "config", nargs="?", metavar="CONFIG", help="TOML run configuration (default configs/default.toml)"
    )
    add_data_options(parser)


def add_model_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("model", metavar="MODEL", help="model file written by groupfit fit or groupfit diagnose")


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
    parser.add_argument("--out", dest="out", metavar=metavar, default=default, help=help)
    if aliases:
        parser.add_argument(*aliases, dest="out", metavar=metavar, help=argparse.SUPPRESS)
    if required:
        parser.set_defaults(out_required=True)


def add_json_option(parser: argparse.ArgumentParser, what: str = "the result") -> None:
    """``--json FILE``: the machine-readable result, ``-`` for stdout."""
    parser.add_argument("--json", metavar="FILE", help=f"write {what} as JSON ('-' for stdout)")


def add_quiet_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def config_with_data_options(args: argparse.Namespace, config_path: str | None) -> dict[str, dict[str, Any]]:
    """The configuration file merged with --data, --time, --temps, --error."""
    config = read_config(config_path)
    override(config, "data", "path", args.data[0] if args.data and len(args.data) == 1 else args.data)
    override(config, "data", "time", args.time)
    override(config, "data", "temps", split_names(args.temps))
    override(config, "data", "error", args.error)
    return config


def load_configured_run(config: dict, path: str | None = None, **options) -> Run:
    """Load the run named by ``path`` (default: the configuration's data path)."""
    data = config["data"]
    path = path or data.get("path")
    if not path:
        raise InputError("no data given: pass --data CSV or set [data] path in the configuration")
    if isinstance(path, (list, tuple)):
        return join_runs(
            [load_run(p, temps=data.get("temps"), time=data["time"], error=data["error"], **options) for p in path]
        )
    return load_run(path, temps=data.get("temps"), time=data["time"], error=data["error"], **options)


def write_json(target: str | None, obj: Any) -> None:
    """Write a JSON result to a file, or to stdout for '-'."""
    if target is None:
        return
    text = to_json(obj)
    if target == "-":
        sys.stdout.write(text)
    else:
        atomic_write_text(target, text)


def report_stream(args: argparse.Namespace):
    """Where the human-readable report goes: stderr when JSON goes to stdout."""
    return sys.stderr if getattr(args, "json", None) == "-" else sys.stdout


def check_output_dir(path: str | Path) -> Path:
    """Create the output folder or say why it cannot be."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{path}: output path exists and is not a folder; choose another --out")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{path}: cannot create the output folder ({exc.strerror})") from None
    return path


class StageProgress:
    """A tqdm bar per named stage, driven by ``(stage, fraction)`` callbacks."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.bars: dict[str, tqdm] = {}

    def __call__(self, stage: str, fraction: float) -> None:
        if not self.enabled:
            return
        bar = self.bars.get(stage)
        if bar is None:
            bar = self.bars[stage] = tqdm(total=1000, desc=stage, leave=False, file=sys.stderr, disable=None)
        bar.update(max(0, int(round(1000 * min(fraction, 1.0))) - bar.n))

    def close(self) -> None:
        for bar in self.bars.values():
            bar.close()
        self.bars.clear()


def add_reference_option(parser: argparse.ArgumentParser) -> None:
    """``--reference COLUMN|start|none``: what the model's temperature inputs are taken relative to."""
    parser.add_argument(
        "--reference",
        metavar="COLUMN|start|none",
        help="take every input minus a reference sensor (e.g. T_amb), minus its first reading ('start'), "
        "or as read ('none'); default: T_amb when the run has that column, else none",
    )


def configured_reference(args: argparse.Namespace, config: dict, run: Run) -> str | None:
    """The reference of ``--reference``, else ``[model] reference``, else T_amb when ``run`` has it."""
    from groupfit.reference import default_reference

    value = getattr(args, "reference", None)
    if value is None:
        value = config["model"].get("reference")
    return default_reference(run.frame, value)
