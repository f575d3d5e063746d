"""The ``groupfit`` command line.

Exit status 0 on success, 2 on bad input (one line on stderr naming the file,
column or value at fault, and nothing half-written).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import threading
from typing import Sequence

from groupfit import __version__
from groupfit.errors import InputError
from groupfit.outputs import OutputPlan


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line and exit status 2."""

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


VERBS = {
    "fit": "optimise hard breaks, fit soft-group coefficients, save the model",
    "compare": "grouped p = 0…P vs global MLR vs physics AR(1) on all runs",
    "diagnose": "trace a model's residual on measured data to a missing effect",
    "simulate": "generate a data set (finite elements or a lumped model)",
    "sweep": "parameter sweep study on local processes or a Dask cluster",
    "replay": "run the run-time switching rule over a recorded run",
    "export": "write the run-time switching rule as C, Structured Text, JSON or a sheet",
    "screw": "ball-screw temperature-field model: identify, predict, compare",
    "iso230": "ISO 230-2 evaluation of bidirectional positioning runs",
}
"""Each verb is a module of :mod:`groupfit.commands` with ``add_parser(verbs)``; the text is its line in --help."""


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; only the verb named in ``argv`` is imported (``groupfit --help`` imports none)."""
    parser = OneLineParser(prog="groupfit", description=__doc__.splitlines()[0].replace("``", ""))
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    verbs = parser.add_subparsers(dest="verb", required=True, parser_class=OneLineParser, metavar="VERB")
    chosen = _chosen_verb(sys.argv[1:] if argv is None else argv)
    for verb, text in VERBS.items():
        if verb == chosen:
            importlib.import_module(f"groupfit.commands.{verb}").add_parser(verbs)
        else:
            verbs.add_parser(verb, help=text)
    return parser


TERMINATED = "terminated"
"""The KeyboardInterrupt a SIGTERM (``kill``, ``timeout``, a service stop) raises: cleaned up as Ctrl-C is."""


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if getattr(args, "out_required", False) and args.out is None:
        parser.error(f"{args.verb}: the following argument is required: --out")
    try:
        with _terminate_as_interrupt(), OutputPlan(force=getattr(args, "force", False)).active():
            return int(args.handler(args) or 0)  # every output written together or none
    except InputError as exc:
        print(f"groupfit {args.verb}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt as exc:
        terminated = exc.args == (TERMINATED,)
        print(f"groupfit {args.verb}: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
        return 128 + (signal.SIGTERM if terminated else signal.SIGINT)


@contextlib.contextmanager
def _terminate_as_interrupt():
    """While a verb runs, SIGTERM raises :data:`TERMINATED` as a KeyboardInterrupt (the main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(TERMINATED)

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _chosen_verb(argv: Sequence[str]) -> str | None:
    """The first word that is not an option, when it names a verb."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in VERBS else None
    return None


def _version() -> str:
    return __version__
