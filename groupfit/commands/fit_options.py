"""The command line of ``groupfit fit``: its options, and the refusal of those a fit would ignore."""

from __future__ import annotations

import argparse

from groupfit.commands import ar1_fit as ar1_commands
from groupfit.commands import common, option_values, reference_options
from groupfit.commands.recalibrate_option import add_recalibrate_option
from groupfit.errors import InputError
from groupfit.heldout.choice import RMS_TOLERANCE
from groupfit.heldout.selection import SELECTION_METHODS
from groupfit.inference.cli import add_interval_options
from groupfit.settings import P_RULES


def add_fit_arguments(fit: argparse.ArgumentParser) -> None:
    """Every option of ``fit``, the grouped model's and ``--model ar1``'s."""
    common.add_run_options(fit)
    fit.add_argument(
        "--p",
        type=whole_or_auto("p"),
        help="number of hard break points; default (or 'auto'): chosen by --choose over 0…pmax",
    )
    fit.add_argument("--pmax", type=int, help="largest p tried when p is chosen (default 3)")
    fit.add_argument(
        "--choose",
        "--p-rule",
        dest="p_rule",
        choices=P_RULES,
        help="how p is chosen: next-run (default: the fewest breaks whose expected next-run error is within one "
        f"standard error, or a factor of {RMS_TOLERANCE:g}, of the least), bic (in sample), target (fewest breaks "
        "with R <= --p-target)",
    )
    fit.add_argument("--p-target", metavar="R", help="target R for --p-rule target: µm, or a percentage like 20%%")
    fit.add_argument("--n", type=int, help="soft offset: samples shared by neighbouring groups")
    fit.add_argument("--c", type=float, help="spacing coefficient: groups hold more than c·M samples")
    fit.add_argument("--objective", choices=("sae", "sse"), help="residual sum to minimise")
    fit.add_argument("--no-intercept", action="store_true", help="fit groups without a constant term")
    fit.add_argument("--search", choices=("ga", "exact"), help="genetic algorithm or exact dynamic programming")
    fit.add_argument("--seed", type=option_values.seed_value, help="seed of the genetic algorithm")
    fit.add_argument(
        "--certify",
        choices=("auto", "yes", "no"),
        help="GA: also run the exact search and print the gap (auto: when cheap; the default)",
    )
    fit.add_argument("--criterion", metavar="COLUMN", help="switching criterion sensor (default: the most active)")
    reference_options.add_reference_option(fit)
    fit.add_argument(
        "--select",
        choices=SELECTION_METHODS,
        help="choose the inputs among --temps on held-out conditions (forward, lasso or cluster)",
    )
    fit.add_argument("--sensors", type=int, metavar="K", help="with --select: how many inputs (default: chosen)")
    fit.add_argument(
        "--ridge",
        type=option_values.ridge_value,
        metavar="ALPHA|auto",
        help="shrink the coefficients of a global model (p = 0) on many collinear inputs by a ridge penalty; "
        "auto: the penalty with the least error on held-out conditions or runs (the default when fit chooses "
        "p and chooses p = 0; 0: least squares)",
    )
    fit.add_argument(
        "--backward",
        type=float,
        metavar="ALPHA",
        help="with --p 0: drop inputs whose t-test p-value exceeds ALPHA, the least significant first, "
        "refitting after each (backward elimination, e.g. 0.05)",
    )
    fit.add_argument(
        "--position",
        metavar="COLUMN",
        help="axis position column (mm) of a run measured at several positions (long table; a wide one has "
        "err_P<mm> columns): fit E(P, T) = K0(T) + c1(T)(P - P0) + ...",
    )
    fit.add_argument(
        "--position-order",
        type=whole_or_auto("order"),
        metavar="N|auto",
        help="with --position: polynomial order in P (default 1: K0 + tanb (P - P0)); auto: chosen by "
        "cross-validation over held-out positions",
    )
    fit.add_argument(
        "--position-ref",
        metavar="MM|middle|min|max",
        help="with --position: the reference position P0 (default: the middle of the measured travel)",
    )
    fit.add_argument(
        "--dead-band",
        type=float,
        metavar="C",
        help="no update of the compensation while every input is within C degC of --dead-band-ref",
    )
    fit.add_argument(
        "--dead-band-ref",
        metavar="COLUMN",
        help="reference sensor of --dead-band (default: the --reference column)",
    )
    common.add_json_option(fit)
    common.add_out_option(fit, "folder for model.json and fit.png")
    common.add_quiet_option(fit)
    common.add_budget_option(fit)
    add_interval_options(fit)
    add_recalibrate_option(fit)
    ar1_commands.add_fit_options(fit)


def whole_or_auto(what: str):
    """The argparse type of an option taking a whole number or 'auto' (``what`` names it in the message)."""

    def value(text: str) -> int | str:
        if text == "auto":
            return text
        try:
            return int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid {what}: {text!r} (a whole number or 'auto')") from None

    return value


def refuse_unused_options(args: argparse.Namespace) -> None:
    """Refuse an option the grouped model's fit would ignore: one of --model ar1's, or how p is chosen when it
    is given."""
    ar1_commands.refuse_ar1_options(args)
    if args.p not in (None, "auto") and (args.p_rule is not None or args.p_target is not None):
        option = "--choose" if args.p_rule is not None else "--p-target"
        raise InputError(
            f"{option}: p is given (--p {args.p}), so nothing is chosen; give --p auto or leave {option} out"
        )
