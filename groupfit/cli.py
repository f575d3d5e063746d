"""The ``groupfit`` command line.

Exit status 0 on success, 2 on bad input (one line on stderr naming the file,
column or value at fault, and nothing half-written).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Sequence

from groupfit.errors import InputError

class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line and exit status 2."""

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def add_data_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", metavar="CSV", help="the run (CSV with a header, one row per sample)")
    parser.add_argument("--time", metavar="COLUMN", help="time column in seconds (default time_s)")
    parser.add_argument("--temps", metavar="A,B,C", help="temperature input columns, comma separated")
    parser.add_argument("--error", metavar="COLUMN", help="thermal-error column in µm (default error_um)")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="groupfit", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    verbs = parser.add_subparsers(dest="verb", required=True, parser_class=OneLineParser, metavar="VERB")

    fit = verbs.add_parser("fit", help="optimise hard breaks, fit soft-group coefficients, save the model")
    fit.add_argument("config", nargs="?", metavar="CONFIG", help="TOML run configuration")
    add_data_options(fit)
    fit.add_argument("--p", type=int, help="number of hard break points")
    fit.add_argument("--n", type=int, help="soft offset: samples shared by neighbouring groups")
    fit.add_argument("--c", type=float, help="spacing coefficient: groups hold more than c·M samples")
    fit.add_argument("--objective", choices=("sae", "sse"), help="residual sum to minimise")
    fit.add_argument("--no-intercept", action="store_true", help="fit groups without a constant term")
    fit.add_argument("--search", choices=("ga", "exact"), help="genetic algorithm or exact dynamic programming")
    fit.add_argument("--seed", type=int, help="seed of the genetic algorithm")
    fit.add_argument("--criterion", metavar="COLUMN", help="switching criterion sensor (default: the most active)")
    fit.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' for stdout)")
    fit.add_argument("--out", metavar="DIR", help="folder for model.json and fit.png")
    fit.add_argument("--quiet", action="store_true", help="no progress bar")
    fit.set_defaults(handler=_run_fit)

    simulate = verbs.add_parser("simulate", help="generate a data set (finite elements or a lumped model)")
    simulate.add_argument("config", metavar="CONFIG", help="TOML scenario configuration")
    simulate.add_argument("-o", "--output", required=True, metavar="CSV", help="data set to write")
    simulate.add_argument("--quiet", action="store_true", help="no progress bar")
    simulate.set_defaults(handler=_run_simulate)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except InputError as exc:
        print(f"groupfit {args.verb}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"groupfit {args.verb}: interrupted", file=sys.stderr)
        return 130


def _version() -> str:
    from groupfit import __version__

    return __version__


def _run_fit(args: argparse.Namespace) -> int:
    from groupfit.commands.fit import run_fit

    return run_fit(args)


def _run_simulate(args: argparse.Namespace) -> int:
    from groupfit.commands.simulate import run_simulate

    return run_simulate(args)
