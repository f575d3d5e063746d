import contextlib
import io
import itertools
import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import settings
from support import SHARED_DATA
from test_switching_models import SYNTHETIC

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.grouping import Constraints, soft_groups
from groupfit.synthetic import simulate_lumped

# The property tests draw the same examples on every run (a red CI is a change, not a draw);
# HYPOTHESIS_PROFILE=explore draws new ones, as bench/bench_model_fuzz.py does at scale.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))

TOOLCHAIN_FIXTURES = {"drivers", "single_driver"}
"""Fixtures that build the C export with gcc: a test using one is marked ``toolchain``."""


def pytest_collection_modifyitems(items):
    """Mark what a test needs from its fixtures and skip conditions, so that no test has to repeat it.

    ``toolchain``: the test uses a fixture that builds C with gcc. ``measured``: the test uses
    :func:`measured_data`, or skips on a condition whose reason names ``shared/data``. Tests that call gcc or
    the Structured Text parsers themselves, and those that run the command in a subprocess (``cli``), say so
    with the marker.
    """
    for item in items:
        fixtures = set(getattr(item, "fixturenames", ()))
        if fixtures & TOOLCHAIN_FIXTURES:
            item.add_marker(pytest.mark.toolchain)
        skips_without_data = any(
            "shared/data" in str(mark.kwargs.get("reason", "")) for mark in item.iter_markers("skipif")
        )
        if "measured_data" in fixtures or skips_without_data:
            item.add_marker(pytest.mark.measured)


@pytest.fixture(scope="session")
def measured_data():
    """The folder of measured data (``../shared/data``); the test is skipped when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"measured data absent: {SHARED_DATA} (a fresh clone has none)")
    return SHARED_DATA


def brute_force_rg(X, y, breaks, n, objective, fit_intercept):
    """Rg straight from the paper's definition: every soft group's residual sum,
    minus each overlap's residuals computed with the earlier group's model."""
    N = len(y)
    A = np.column_stack([np.ones(N), X]) if fit_intercept else X
    measure = (lambda r: np.sum(np.abs(r))) if objective == "sae" else (lambda r: np.sum(r**2))
    total, models = 0.0, []
    for first, last in soft_groups(breaks, N, n):
        coef = np.linalg.lstsq(A[first - 1 : last], y[first - 1 : last], rcond=None)[0]
        models.append(coef)
        total += measure(y[first - 1 : last] - A[first - 1 : last] @ coef)
    for k, b in enumerate(breaks):
        total -= measure(y[b - n : b] - A[b - n : b] @ models[k])
    return total


def brute_force_optimum(X, y, p, n, c, objective, fit_intercept):
    """Best feasible break vector by enumerating every combination."""
    N = len(y)
    M = X.shape[1] + int(fit_intercept)
    constraints = Constraints.for_model(N, n, c, M)
    best, best_breaks = np.inf, None
    for breaks in itertools.combinations(range(1, N), p):
        if constraints.is_feasible(breaks):
            value = brute_force_rg(X, y, list(breaks), n, objective, fit_intercept)
            if value < best:
                best, best_breaks = value, list(breaks)
    return best_breaks, best


@pytest.fixture(scope="session")
def lumped_run():
    """The paper's duty cycle on the lumped thermal network: 300 samples, 4 sensors."""
    frame = simulate_lumped({})
    return frame[["T1", "T2", "T3", "T4"]].to_numpy(), frame["error_um"].to_numpy()


@pytest.fixture(scope="module")
def drivers(tmp_path_factory):
    """Build (and cache, per test module) the C driver of a model: ``drivers(label, model, kind)``.

    ``kind``: ``"double"``, ``"single"`` (``GF_USE_FLOAT``) or ``"sanitized"`` (ASan/UBSan). Skips without gcc.
    """
    import shutil

    from groupfit.export import render, write
    from groupfit.export.harness import build_driver

    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    built = {}

    def get(label, model, kind="double"):
        key = (label, kind)
        if key not in built:
            folder = tmp_path_factory.mktemp(f"c_{len(built)}")
            write(render(model, "c"), folder)
            if kind == "sanitized":
                flags = ("-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all")
                built[key] = build_driver(folder, folder / "driver", flags=flags)
            else:
                built[key] = build_driver(folder, folder / "driver", single=(kind == "single"))
        return built[key]

    return get


DIAG_SCENARIOS = Path(__file__).resolve().parents[1] / "datasets"
"""Where the finite-element diagnosis data sets ``diag_<scenario>_model.csv`` / ``_validate.csv`` live."""


@pytest.fixture(scope="session")
def diagnosed_scenario(tmp_path_factory):
    """``diagnosed_scenario(name)``: ``groupfit fit --p 0 --reference none`` on the FE data set ``diag_<name>_model``,
    then ``groupfit diagnose`` with ``diag_<name>_validate``, run once per session for each scenario.

    Returns the ``--json`` result (a dict), the model file's path and the printed report. Tests read them and
    must not change the files.
    """
    done = {}

    def get(name):
        if name not in done:
            folder = tmp_path_factory.mktemp(f"diag_{name}")
            data = DIAG_SCENARIOS / f"diag_{name}_model.csv"
            fit = ["fit", "--data", str(data), "--temps", "T1,T2,T3,T4", "--p", "0", "--reference", "none"]
            assert main([*fit, "--out", str(folder / "model"), "--quiet"]) == 0
            validate = DIAG_SCENARIOS / f"diag_{name}_validate.csv"
            args = ["diagnose", str(folder / "model" / "model.json"), "--data", str(data), "--validate", str(validate)]
            report = io.StringIO()
            with contextlib.redirect_stdout(report):
                status = main([*args, "--out", str(folder / "diagnose"), "--json", str(folder / "diagnose.json")])
            assert status == 0
            result = json.loads((folder / "diagnose.json").read_text())
            done[name] = (result, folder / "model" / "model.json", report.getvalue())
        return done[name]

    return get


@pytest.fixture
def fitted_on_monday(tmp_path):
    """``fitted_on_monday(monday, tuesday, temps)``: both runs written as CSV and ``groupfit fit --p 0`` run on the
    first with the fit's defaults; returns the two paths and the model file's path."""

    def fit(monday, tuesday, temps):
        data, other = tmp_path / "monday.csv", tmp_path / "tuesday.csv"
        monday.to_csv(data, index=False)
        tuesday.to_csv(other, index=False)
        args = [
            "fit",
            "--data",
            str(data),
            "--temps",
            ",".join(temps),
            "--p",
            "0",
            "--quiet",
            "--out",
            str(tmp_path / "m"),
        ]
        assert main(args) == 0
        return data, other, tmp_path / "m" / "model.json"

    return fit


@pytest.fixture(scope="session")
def synthetic():
    """The synthetic cycle as a table and as groupfit reads it (inputs T1-T4): the truth a log of the same run
    written in another form is read against."""
    return pd.read_csv(SYNTHETIC), load_run(SYNTHETIC, temps=["T1", "T2", "T3", "T4"])
