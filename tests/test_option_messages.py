"""Refusals that say what to change: the limit that binds, the sign of an interval, a wide position table."""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import VERBS, build_parser, main
from groupfit.errors import InputError
from groupfit.grouping import Constraints
from groupfit.probe_intervals import parse_intervals


@pytest.mark.parametrize(
    "n, c, lower",
    [(1000, 3.0, "lower n (the soft offset)"), (3, 100.0, "lower c"), (30, 3.0, "lower c")],
)
def test_a_model_that_cannot_fit_names_the_limit_that_binds(n, c, lower):
    constraints = Constraints.for_model(532, n, c, 7)
    assert constraints.max_breaks() < 0 or n == 30
    if constraints.max_breaks() >= 0:  # c·M = 21 < n = 30 < N: fits, the largest p is named instead
        with pytest.raises(InputError, match="the largest feasible p is"):
            constraints.require(constraints.max_breaks() + 1, c, 7)
        return
    with pytest.raises(InputError, match=f"give more samples or {lower.replace('(', '[(]').replace(')', '[)]')}$"):
        constraints.require(2, c, 7)


@pytest.mark.parametrize("text", ["-5", "-5m", "-0.5h", "0"])
def test_a_negative_or_zero_check_interval_is_named_as_such(text):
    with pytest.raises(InputError, match=f"'{text}' must be longer than 0"):
        parse_intervals(text)


def test_a_wide_position_table_without_position_points_to_the_option(tmp_path, capsys):
    times = np.arange(20) * 600.0
    wide = pd.DataFrame({"time_s": times, "T1": 20 + times / 3600, "T2": 21 + times / 7200})
    for mm in (0, 100, 200):
        wide[f"err_P{mm:04d}"] = 0.01 * mm + wide["T1"] - 20
    wide.to_csv(tmp_path / "wide.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "wide.csv"), "--temps", "T1,T2", "--out", str(tmp_path / "o")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "err_P0000, err_P0100, err_P0200" in err and "--position COLUMN" in err
    assert main([*args, "--position", "P_mm", "--quiet"]) == 0  # as advised


def _verbs(parser: argparse.ArgumentParser, prefix=()):
    """Every verb and sub-verb's parser (the leaves: the ones a command line ends in)."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield prefix, parser
        return
    for name, sub in subs[0].choices.items():
        yield from _verbs(sub, (*prefix, name))


def test_every_verb_takes_quiet():
    missing = []
    for verb in VERBS:  # the parser builds the verb it is given
        for name, parser in _verbs(build_parser([verb])):
            if name[0] == verb and "--quiet" not in parser._option_string_actions:
                missing.append(" ".join(name))
    assert missing == []
