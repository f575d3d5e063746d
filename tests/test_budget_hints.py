"""An exact search over the budget is refused with advice the refusing verb takes."""

import argparse
import re

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import build_parser, main


@pytest.fixture(scope="module")
def long_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("long") / "long.csv"
    rng = np.random.default_rng(0)
    n = 9000
    temps = 20 + np.cumsum(rng.normal(0, 0.01, (n, 4)), axis=0)
    error = temps @ np.array([1.0, -0.5, 0.3, 0.2]) + rng.normal(0, 0.1, n)
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"]).assign(error_um=error)
    frame.insert(0, "time_s", np.arange(n) * 10.0)
    frame.to_csv(path, index=False)
    return path


def options_of(verb: str) -> set[str]:
    verbs = next(a for a in build_parser([verb])._actions if isinstance(a, argparse._SubParsersAction))  # noqa: SLF001
    return {flag for action in verbs.choices[verb]._actions for flag in action.option_strings}  # noqa: SLF001


@pytest.mark.parametrize(
    "verb, args",
    [("fit", ["--search", "exact", "--p", "3"]), ("compare", ["--heat", "none"])],
)
def test_the_refusal_names_only_options_of_its_verb(tmp_path, capsys, long_run, verb, args):
    assert main([verb, "--data", str(long_run), *args, "--out", str(tmp_path / "out")]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "over the budget" in line and not (tmp_path / "out").exists()
    advised = set(re.findall(r"(--[a-z][a-z-]*)", line))
    assert advised and advised <= options_of(verb), advised - options_of(verb)
