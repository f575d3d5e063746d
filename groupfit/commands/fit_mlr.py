"""``groupfit fit --p 0``: the regression's significance tests, and dropping inputs by them (``--backward``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from groupfit.data import Run
from groupfit.errors import InputError
from groupfit.models.mlr import MLR, backward_elimination


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


__all__ = ["backward_run", "statistics"]
