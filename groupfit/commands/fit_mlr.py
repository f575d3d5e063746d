"""``groupfit fit --p 0``: the regression's significance tests, and dropping inputs by them (``--backward``)."""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np
import pandas as pd

from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.models.mlr import MLR, backward_elimination


def add_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--backward",
        type=float,
        metavar="ALPHA",
        help="with --p 0: drop inputs whose t-test p-value exceeds ALPHA, the least significant first, "
        "refitting after each (backward elimination, e.g. 0.05)",
    )


def backward_run(run: Run, alpha: float, *, p, fit_intercept: bool) -> tuple[Run, dict]:
    """The run restricted to the inputs backward elimination keeps, and how it chose them."""
    if p != 0:
        raise InputError("--backward drops inputs of a global regression: use it with --p 0")
    measured = np.isfinite(run.error)
    chosen = backward_elimination(
        run.temps[measured], run.error[measured], list(run.temp_names), alpha=alpha, fit_intercept=fit_intercept
    )
    keep = [run.temp_names.index(name) for name in chosen["inputs"]]
    return replace(run, temps=run.temps[:, keep], temp_names=tuple(chosen["inputs"])), {"method": "backward", **chosen}


def statistics(run: Run, *, fit_intercept: bool) -> dict:
    """t and p per coefficient, F and its p, R² and adjusted R² of the global regression on ``run``."""
    named = pd.DataFrame(run.temps, columns=list(run.temp_names))
    return MLR(fit_intercept=fit_intercept).fit(named, run.error).statistics_


def backward_summary(selection: dict) -> str:
    dropped = ", ".join(f"{d['name']} (t = {d['t']:.2f}, p = {d['p_value']:.3g})" for d in selection["dropped"])
    return (
        f"inputs  backward elimination at alpha = {selection['alpha']:g}: kept {', '.join(selection['inputs'])} "
        f"of {selection['candidates']}; dropped {dropped or 'none'}"
    )


def statistics_summary(stats: dict) -> str:
    """The tests as ``fit --p 0`` prints them."""
    terms = ", ".join(f"{t['name']} t = {t['t']:.3g} (p = {t['p_value']:.3g})" for t in stats["terms"])
    f_text = (
        f"F({stats['f_dof'][0]:g}, {stats['f_dof'][1]:g}) = {stats['f_value']:.4g} (p = {stats['f_p_value']:.3g}); "
        if stats["f_value"] is not None
        else ""
    )
    centred = "" if stats["centred"] else " (uncentred: no intercept)"
    return (
        f"tests   {terms}\n        {f_text}R² = {stats['r_squared']:.5f}, adjusted R² = "
        f"{stats['adjusted_r_squared']:.5f}{centred}, σ = {stats['sigma_um']:.3g} µm"
    )


__all__ = ["add_options", "backward_run", "backward_summary", "statistics", "statistics_summary"]
