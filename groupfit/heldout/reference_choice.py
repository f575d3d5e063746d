"""The reference of the inputs when none is configured: the air's temperature, or none, by the next-run error.

The default reference is the ambient column (``T_amb``, or the ``--ambient``
column): every input minus the air's temperature. That is right for an error
that follows the parts' rises over the air, as a structure whose parts and
measuring loop all expand with the room does. An error measured against a
length that does not follow the room (a master at 20 °C) follows the parts'
own temperatures instead; inputs taken over the air then lose the room's
level, and a day warmer or colder than the modelling run's is off by the
whole change.

One run tells the two apart only when its ambient moves: then each reference
is scored by the same folds that imitate a next run
(:func:`groupfit.heldout.expect.expect_next_run`, each choosing its own p),
and "none" replaces the default only when its expected error is below the
default's by more than one standard error (the one-standard-error rule, the
default taken as the simpler model). An ambient that stays within its own
noise leaves the question open, and the default stands.

When the ambient moves but neither reference is better by a standard error,
the run cannot tell the two apart either; the default stands, and a note says
what a day at another air level would cost if the error follows the parts' own
temperatures: the least-squares model on the absolute readings moves by the
sum of its coefficients for every °C all parts and the air move together
(:func:`air_level_slope`), which the model over the air does not follow.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import pandas as pd

from groupfit.data import Run, measured_rows
from groupfit.heldout.expect import NextRunExpectation, expect_next_run
from groupfit.reference import is_column_reference, with_reference

SIGNAL_TO_NOISE = 3.0
"""The ambient moves when its standard deviation exceeds this many times its sample-to-sample scatter."""
RULE = "none only when its expected next-run error is below the ambient reference's by more than a standard error"


def ambient_signal_to_noise(columns: Sequence[np.ndarray]) -> tuple[float, float]:
    """The ambient's standard deviation over ``columns`` (one per run; °C) and its ratio to the white scatter.

    The scatter is ``sqrt(mean(Δ²) / 2)`` of the sample-to-sample changes within each run: the standard
    deviation of a white noise, which a steady reading shows as its whole spread (ratio ≈ 1).
    """
    values = [np.asarray(c, dtype=float) for c in columns]
    values = [v[np.isfinite(v)] for v in values]
    joined = np.concatenate(values) if values else np.array([])
    steps = np.concatenate([np.diff(v) for v in values if len(v) > 1] or [np.array([])])
    if len(joined) < 3 or len(steps) == 0:
        return 0.0, 0.0
    spread = float(np.std(joined))
    scatter = float(np.sqrt(np.mean(steps**2) / 2.0))
    if scatter == 0.0:
        return spread, (np.inf if spread > 0.0 else 0.0)
    return spread, spread / scatter


@dataclass(frozen=True)
class ReferenceChoice:
    """The reference chosen among the ambient column and none, and the evidence."""

    reference: str | None
    ambient: str
    spread_c: float
    """The ambient's standard deviation over the runs (°C)."""
    signal_to_noise: float
    expectations: dict
    """``{ambient: NextRunExpectation, None: NextRunExpectation}`` when both were scored, else empty."""
    told_apart: bool = True
    """Whether the expected errors of the two references differ by more than a standard error (either way)."""
    air_slope_um_per_c: float = math.nan
    """The absolute readings' least-squares model's change for every °C the parts and the air move together."""

    @property
    def scored(self) -> bool:
        return bool(self.expectations)

    def expected(self, reference) -> tuple[Any, float] | None:
        """The candidate (p) ``reference`` chooses and its expected next-run RMS (µm)."""
        expectation = self.expectations.get(reference)
        if expectation is None:
            return None
        return expectation.candidates[expectation.chosen], expectation.expected()[0]

    def reason(self) -> str:
        if not self.scored:
            return (
                f"the ambient {self.ambient} stays within its noise (sd {self.spread_c:.3g} °C, "
                f"{self.signal_to_noise:.2g} × its sample-to-sample scatter): the run cannot tell whether the "
                "error follows the air, and the default stands"
            )
        (p_amb, amb), (p_none, none) = self.expected(self.ambient), self.expected(None)
        compared = f"none {none:.3g} µm (p = {p_none}) against {self.ambient} {amb:.3g} µm (p = {p_amb})"
        if self.reference is None:
            return f"expected next-run RMS {compared}: the error follows the parts' own temperatures"
        return f"expected next-run RMS {compared}: none is not better by a standard error, the default stands"

    def note(self) -> str | None:
        """The note when the ambient moves and the run cannot tell the references apart; None otherwise."""
        if not self.scored or self.told_apart or not math.isfinite(self.air_slope_um_per_c):
            return None
        (_, amb), (_, none) = self.expected(self.ambient), self.expected(None)
        slope = abs(self.air_slope_um_per_c)
        level = f", the expected {amb:.3g} µm at {amb / slope:.2g} °C" if slope > 0 else ""
        return (
            f"the run cannot tell whether the error follows the parts' rises over {self.ambient} or their own "
            f"temperatures (expected next-run RMS {amb:.3g} against {none:.3g} µm, within a standard error): if "
            f"it follows their own, the model is off by about {slope:.3g} µm for every °C a day's air differs "
            f"from this run's{level}; record a run on a day of another air temperature and fit on both "
            "(--data A B), or name the reference the measuring set-up calls for (--reference none or "
            f"--reference {self.ambient})"
        )

    def line(self) -> str:
        """The report's line (``fit``, ``compare``)."""
        chosen = "none (absolute readings)" if self.reference is None else f"{self.reference} (the default)"
        moves = f"{self.ambient} moves by sd {self.spread_c:.3g} °C"
        return f"reference {chosen}, chosen by the next-run estimate ({moves}; {self.reason()})"

    def to_json(self) -> dict[str, Any]:
        candidates = []
        for reference in (self.ambient, None):
            found = self.expected(reference)
            if found is not None:
                candidates.append({"reference": reference, "p": found[0], "expected_next_run_rms_um": found[1]})
        return {
            "chosen": self.reference,
            "default": self.ambient,
            "rule": RULE,
            "ambient_sd_c": self.spread_c,
            "ambient_signal_to_noise": self.signal_to_noise if math.isfinite(self.signal_to_noise) else None,
            "candidates": candidates,
            "reason": self.reason(),
            "told_apart": self.told_apart if self.scored else None,
            "air_slope_um_per_c": self.air_slope_um_per_c if math.isfinite(self.air_slope_um_per_c) else None,
            "note": self.note(),
        }


def choose_reference(
    runs: Sequence[Run],
    ambient: str,
    p_values: Sequence[int],
    *,
    n: int = 3,
    c: float = 3.0,
    fit_intercept: bool = True,
) -> ReferenceChoice:
    """The ambient column or none as the inputs' reference of ``runs`` (module docstring).

    ``runs``: the runs as read (no reference applied), with a measured error on
    every row. Both references are scored on the same rows (those where the
    ambient is read) and the same folds (the ambient is never an operating
    column). Raises ``ValueError`` when the runs are too short for the estimate.
    """
    bases = [_ambient_rows(run, ambient) for run in runs]
    spread, ratio = ambient_signal_to_noise([_column(run, ambient) for run in bases])
    slope = air_level_slope(bases, fit_intercept=fit_intercept)
    if not ratio > SIGNAL_TO_NOISE:
        return ReferenceChoice(ambient, ambient, spread, ratio, {}, air_slope_um_per_c=slope)
    settings = {"n": n, "c": c, "fit_intercept": fit_intercept}
    over_air = expect_next_run([with_reference(run, ambient) for run in bases], p_values, **settings)
    absolute = expect_next_run(
        [dataclasses.replace(run, frame=run.frame.drop(columns=[ambient])) for run in bases], p_values, **settings
    )
    expectations: dict = {ambient: over_air, None: absolute}
    none_better = _clearly_better(absolute, over_air)
    told_apart = none_better or _clearly_better(over_air, absolute)
    chosen = None if none_better else ambient
    return ReferenceChoice(chosen, ambient, spread, ratio, expectations, told_apart, slope)


def air_level_slope(runs: Sequence[Run], *, fit_intercept: bool = True) -> float:
    """The sum of the coefficients of the least-squares global model of the error on the absolute readings (µm/°C).

    A day whose air is ΔT warmer leaves every part ΔT warmer at the same rises:
    a model on the absolute readings then moves by this sum times ΔT, and one
    over the air not at all. NaN when the runs hold too few rows to fit it.
    """
    temps = np.vstack([run.temps for run in runs])
    error = np.concatenate([run.error for run in runs])
    rows = np.isfinite(temps).all(axis=1) & np.isfinite(error)
    design = temps[rows]
    if fit_intercept:
        design = np.column_stack([np.ones(len(design)), design])
    if len(design) <= design.shape[1]:
        return math.nan
    coef = np.linalg.lstsq(design, error[rows], rcond=None)[0]
    return float(np.sum(coef[int(fit_intercept) :]))


def default_reference_choice(
    runs: Sequence[Run], default: str | None, p_values: Sequence[int], *, n: int, c: float, fit_intercept: bool
) -> ReferenceChoice | None:
    """:func:`choose_reference` when the default reference ``default`` is a column (the ambient) and the runs
    are long enough for the estimate; None otherwise (the default stands unquestioned)."""
    if not is_column_reference(default) or not p_values or any(not isinstance(p, int) or p < 0 for p in p_values):
        return None
    try:
        return choose_reference(
            [measured_rows(run) for run in runs], default, p_values, n=n, c=c, fit_intercept=fit_intercept
        )
    except ValueError:
        return None


def _clearly_better(candidate: NextRunExpectation, default: NextRunExpectation) -> bool:
    """Whether ``candidate``'s chosen model's pooled MSE plus its standard error is below the default's."""
    mean, error = candidate.scores.pooled()
    default_mean, _ = default.scores.pooled()
    spread = error[candidate.chosen] if np.isfinite(error[candidate.chosen]) else np.inf
    return bool(mean[candidate.chosen] + spread < default_mean[default.chosen])


def _column(run: Run, name: str) -> np.ndarray:
    return pd.to_numeric(run.frame[name], errors="coerce").to_numpy(dtype=float)


def _ambient_rows(run: Run, ambient: str) -> Run:
    """``run`` on the rows where the ambient and every input are read."""
    rows = np.isfinite(_column(run, ambient)) & np.isfinite(run.temps).all(axis=1)
    if rows.all():
        return run
    return dataclasses.replace(
        run,
        time=run.time[rows],
        temps=run.temps[rows],
        error=run.error[rows],
        frame=run.frame.loc[rows].reset_index(drop=True),
    )


__all__ = [
    "RULE",
    "SIGNAL_TO_NOISE",
    "ReferenceChoice",
    "air_level_slope",
    "ambient_signal_to_noise",
    "choose_reference",
    "default_reference_choice",
]
