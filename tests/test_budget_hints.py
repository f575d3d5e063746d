"""An exact search over the budget: `fit` refuses it with advice it takes; `compare` compares the GA's
models on a path marked not certified."""

import argparse
import json
import re
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import build_parser, main
from groupfit.commands import common
from groupfit.search.exact import estimate_exact_cost


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


def test_fits_refusal_names_only_options_fit_takes(tmp_path, capsys, long_run):
    args = ["fit", "--data", str(long_run), "--search", "exact", "--p", "3", "--out", str(tmp_path / "out")]
    assert main(args) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "over the budget" in line and not (tmp_path / "out").exists()
    advised = set(re.findall(r"(--[a-z][a-z-]*)", line))
    assert advised and advised <= options_of("fit"), advised - options_of("fit")


def test_compare_over_the_budget_compares_the_gas_models_on_a_path_it_marks_uncertified(tmp_path, capsys, long_run):
    out = tmp_path / "c.json"
    args = ["compare", "--data", str(long_run), "--heat", "none", "--pmax", "2", "--out", str(tmp_path / "cmp")]
    assert main([*args, "--json", str(out), "--quiet"]) == 0
    note = next(line for line in capsys.readouterr().out.splitlines() if "over the budget" in line)
    assert "not certified" in note and set(re.findall(r"(--[a-z][a-z-]*)", note)) <= options_of("compare")
    result = json.loads(out.read_text())
    path = result["exact_path"]
    assert path["certified"] is False
    grouped = {r["p"]: r for r in result["rows"] if r["model"] == "grouped"}
    assert path["breaks"][1:] == [grouped[1]["breaks"], grouped[2]["breaks"]]  # the GA's own models
    assert path["R"][1:] == pytest.approx([grouped[1]["R_um"], grouped[2]["R_um"]], rel=1e-9)
    mlr = next(r for r in result["rows"] if r["model"] == "mlr")
    assert path["R"][0] == pytest.approx(mlr["R_um"], rel=1e-6)  # p = 0: the least-squares fit, exact


@pytest.mark.parametrize("n_samples", [3000, 9000, 20000, 60000])
def test_the_sse_objective_is_advised_only_when_it_is_within_the_budget(n_samples):
    args = argparse.Namespace(objective=None, search=None, no_budget=False)
    run = SimpleNamespace(n_samples=n_samples, period=1.0, source="run.csv")
    over = common.over_budget(args, run, 17, "sae", 3, "the exact search")
    sse = estimate_exact_cost(n_samples, 17, "sse", 3)
    sse_within = sse.seconds <= common.EXACT_BUDGET_SECONDS and sse.bytes <= common.EXACT_BUDGET_BYTES
    if over is not None:
        assert any("--objective sse" in hint for hint in over[1]) == sse_within
