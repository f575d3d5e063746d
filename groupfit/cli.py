"""The ``groupfit`` command line.

Exit status 0 on success, 2 on bad input (one line on stderr naming the file,
column or value at fault, and nothing half-written).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from typing import Sequence

from groupfit.errors import InputError


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line and exit status 2."""

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


VERBS = ("fit", "compare", "diagnose", "simulate", "sweep", "replay", "export", "screw")
"""Each verb is a module of :mod:`groupfit.commands` with ``add_parser(verbs)``."""


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="groupfit", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    verbs = parser.add_subparsers(dest="verb", required=True, parser_class=OneLineParser, metavar="VERB")
    for verb in VERBS:
        importlib.import_module(f"groupfit.commands.{verb}").add_parser(verbs)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except InputError as exc:
        print(f"groupfit {args.verb}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print(f"groupfit {args.verb}: interrupted", file=sys.stderr)
        return 130


def _version() -> str:
    from groupfit import __version__

    return __version__
