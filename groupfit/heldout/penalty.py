"""The ridge penalty ``fit`` gives a global model it chose, as ``compare`` and the calibration bench reproduce it.

``fit`` without ``--p`` and ``--ridge`` that chooses p = 0 fits the global
model with ``--ridge auto``: the penalty with the least error on held-out
operating conditions (:func:`groupfit.heldout.check.ridge_setting`).
"""

from __future__ import annotations

from typing import Any, Sequence

import pandas as pd

from groupfit.data import Run
from groupfit.heldout.check import ridge_setting
from groupfit.heldout.expect import expect_next_run
from groupfit.heldout.records import RidgeSetting


def run_penalty(run: Run, *, fit_intercept: bool = True, frames: Sequence[pd.DataFrame] | None = None) -> RidgeSetting:
    """The penalty of the global model on ``run``: the least error on its held-out conditions, or on its runs
    held out when ``run`` joins several (``frames``: their tables, in order)."""
    exclude = {run.time_name, run.error_name, *run.temp_names}
    frames = [run.frame] if frames is None else list(frames)
    return ridge_setting("auto", 0, run.temps, run.error, frames, exclude, fit_intercept=fit_intercept, default=True)


def penalised_expectation(run: Run, *, fit_intercept: bool = True, parts: Sequence[Run] = ()) -> dict[str, Any]:
    """The penalty ``fit`` gives the global model it chooses on ``run`` and that model's expected next-run RMS.

    ``parts``: the runs ``run`` joins, when it joins several; the penalty and
    the expectation then hold each of them out in turn.
    """
    several = len(parts) > 1
    ridge = run_penalty(run, fit_intercept=fit_intercept, frames=[part.frame for part in parts] if several else None)
    expected, (low, high) = expect_next_run(
        list(parts) if several else [run], (0,), fit_intercept=fit_intercept, ridge_alpha=ridge.alpha
    ).expected()
    return {
        "alpha": ridge.alpha,
        "folds": ridge.folds,
        "expected_next_run_rms_um": expected,
        "expected_next_run_range_um": [low, high],
    }


def penalty_lines(penalty: dict[str, Any] | None) -> list[str]:
    """``compare``'s line on the penalty fit's choice gets (none without one)."""
    if penalty is None or not penalty["alpha"] > 0:
        return []
    return [
        f"fit's choice p = 0 gets the ridge penalty alpha = {penalty['alpha']:g} (the least error on "
        f"{penalty['folds']}): expected next-run RMS {penalty['expected_next_run_rms_um']:.3g} µm"
    ]


__all__ = ["penalised_expectation", "penalty_lines", "run_penalty"]
