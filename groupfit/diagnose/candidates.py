"""Candidate explanations of a residual, and how much of it each explains on held-out conditions.

Candidates are every usable column the model does not use (ambient
temperature, spindle speed, on/off of other heat sources, unused sensors), as
measured, low-passed over a grid of time constants (thermal lag),
differentiated and delayed. A speed (an operating column with more than two
levels) enters through the bearing-heat law ``(n / scale)^k`` (k = 5/3 by
default, or fitted over :data:`FITTED_EXPONENTS`), as measured, low-passed
and times the hours it has run without a break (speed × on-time). Lags of
operating columns (speeds, on/off of heat sources) start from rest, lags of
everything else from the first reading
(:mod:`groupfit.features`). Transforms of the model's own inputs are tried
only when asked for. A column is left out, with the
reason, when it is not numeric, has non-finite values, is constant (a dead
sensor) or is a displacement (another probe's error is not a cause the
controller can read).

The score is the share of the model's error a candidate removes on held-out
folds that imitate a new run (:mod:`groupfit.heldout.folds`): each fold is
predicted by the model's own regression (each group's inputs in its own
columns) refitted on the other folds, with and without the candidate as one
more regressor. A candidate that only fits the conditions it was fitted on
scores near zero or below.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.columns import is_sensor_column
from groupfit.features import Feature
from groupfit.heldout.scorer import HeldOutScorer

TAUS_S = (600.0, 1200.0, 1800.0, 3600.0, 5400.0, 7200.0, 10800.0, 14400.0, 21600.0, 28800.0)
DELAYS = (1, 3, 10)
HEAT_EXPONENT = 5.0 / 3.0
"""Bearing heat ∝ n^(5/3) (Palmgren's friction moment times speed), as the FE model uses."""
FITTED_EXPONENTS = (1.0, 4.0 / 3.0, 5.0 / 3.0, 2.0)
"""Exponents tried when the heat-law exponent is fitted (``heat_exponent="fit"``)."""
COLLINEAR_R = 0.95
"""A candidate correlated this closely (|r|) with one of the model's inputs is *collinear* with it."""
RANK_DIGITS = 9
"""Decimals of the score candidates are ranked by; scores that agree to these are a tie."""
FOLD_TIE = 10.0**-RANK_DIGITS
"""A fold whose error ratio is within this of 1 is not improved: a candidate that leaves the fit as it was
moves its folds by the last digits of the linear algebra alone, which differ from one machine to another."""


@dataclass(frozen=True)
class Candidate:
    """A feature and how it scored on the held-out folds."""

    feature: Feature
    score: float
    """Share of the held-out squared error the candidate removes: 1 − SSE_with / SSE_without."""
    coefficient: float
    explained_rms_um: float
    """RMS (µm) of the residual the candidate removes out of sample: √((SSE_without − SSE_with)/N)."""
    fold_sse: tuple[float, ...] = ()
    """SSE_with on each held-out fold (µm²)."""
    fold_ratios: tuple[float, ...] = ()
    """SSE_with / SSE_without on each held-out fold."""
    own_input: bool = False
    """A transform of one of the model's own inputs."""
    collinearity: float = 0.0
    """Largest |r| between the candidate and one of the model's inputs."""
    over: str | None = None
    """The model's reference column when the candidate is taken over it (``feature − reference``: the lag of a
    part behind the air, for a model of rises over the air); None when taken as computed."""

    def describe(self) -> str:
        """The transform in words, with the reference it is taken over."""
        words = self.feature.describe()
        return words if self.over is None else f"{words}, over {self.over}"

    @property
    def rank(self) -> float:
        """The score to rank by: rounded to ``RANK_DIGITS`` decimals, so that candidates that score alike (a
        low-pass of the speed and of spindle-on when the speed is one step) keep the order they were tried in
        whatever the last digits the linear algebra of the machine gives them."""
        return round(self.score, RANK_DIGITS)

    @property
    def folds_improved(self) -> float:
        """Share of the held-out folds on which the candidate lowers the error."""
        return self.n_folds_improved / len(self.fold_ratios) if self.fold_ratios else 0.0

    @property
    def n_folds_improved(self) -> int:
        """Number of the held-out folds on which the candidate lowers the error."""
        return int(np.count_nonzero(np.asarray(self.fold_ratios) < 1.0 - FOLD_TIE))

    def family(self) -> tuple:
        """Candidates that differ only in their low-pass time constant."""
        f = self.feature
        return (f.column, f.transform, f.exponent, f.scale, self.over)

    def to_dict(self) -> dict:
        return {
            "column": self.feature.column,
            "transform": self.feature.transform,
            "tau_s": self.feature.tau_s,
            "delay_samples": self.feature.delay_samples or None,
            "exponent": self.feature.exponent,
            "scale": self.feature.scale,
            "name": self.feature.name,
            "over_reference": self.over,
            "description": self.describe(),
            "score": self.score,
            "explained_rms_um": self.explained_rms_um,
            "folds_improved": self.folds_improved,
            "fold_ratios": list(self.fold_ratios),
            "own_input": self.own_input,
            "collinearity": self.collinearity,
        }


EXOGENOUS_R = 0.5
"""An unused sensor whose correlation with every lag of every heat source stays below this follows something
else than the machine's heat (the air, when no column is named as the ambient)."""


def heat_law_scale(values: np.ndarray) -> float:
    """A round reference for the power stage: 1000 for speeds in the thousands of r/min."""
    top = float(np.max(np.abs(values)))
    return float(10.0 ** np.floor(np.log10(top))) if top > 0 else 1.0


def candidate_features(
    columns: list[str],
    model_inputs: list[str],
    frame: pd.DataFrame,
    operating: Sequence[str] = (),
    heat_exponent: float | str = HEAT_EXPONENT,
    *,
    sensor_transforms: bool = True,
    sensor_columns: frozenset[str] | None = None,
) -> list[Feature]:
    """The transforms tried.

    Every column: as measured (unused columns only), low-pass over
    :data:`TAUS_S`, derivative, delays; lags of ``operating`` columns start
    from rest. A speed among ``operating`` (see :func:`speed_like`) enters
    through the heat law instead of linearly, as measured, low-passed and
    times the hours it has run without a break (``ontime``);
    ``heat_exponent="fit"`` tries :data:`FITTED_EXPONENTS` (1 is the column
    itself) instead of one exponent. With ``sensor_transforms=False`` an
    unused temperature sensor (``sensor_columns``, by default those
    :func:`is_sensor_column` names) enters as measured
    only: a lag of a machine temperature re-weights what it reads, as a lag
    of the model's own inputs does.
    """
    speeds = speed_like(frame, operating)
    exponents = FITTED_EXPONENTS if heat_exponent == "fit" else (float(heat_exponent),)
    features = []
    for column in [*columns, *model_inputs]:
        start = "rest" if column in operating else "steady"
        if column in speeds:
            values = frame[column].to_numpy(float)
            for k in exponents:
                signed = k == 1.0 and values.min() >= 0  # n itself; with a direction sign, |n|
                power = {} if signed else {"exponent": k, "scale": heat_law_scale(values)}
                features.append(Feature(column, **power))
                features.extend(Feature(column, "lowpass", tau_s=tau, start=start, **power) for tau in TAUS_S)
                features.append(Feature(column, "ontime", start="rest", **power))
            continue
        if column in columns:
            features.append(Feature(column))
            is_sensor = column in sensor_columns if sensor_columns is not None else is_sensor_column(column)
            if not sensor_transforms and is_sensor:
                continue
        features.extend(Feature(column, "lowpass", tau_s=tau, start=start) for tau in TAUS_S)
        features.append(Feature(column, "derivative"))
        features.extend(Feature(column, "delay", delay_samples=d, start=start) for d in DELAYS)
    return features


def speed_like(frame: pd.DataFrame, operating: Sequence[str]) -> list[str]:
    """Operating columns that set a level (more than two magnitudes): a speed, a feed.

    The sign is a direction (M3/M4, a feed forward or back): the heat law takes the magnitude.
    """
    out = []
    for column in operating:
        values = np.abs(frame[column].to_numpy(dtype=float))
        if len(np.unique(values)) > 2:
            out.append(column)
    return out


def within_one_se(candidate: Candidate, best: Candidate, standard_errors: float = 1.0) -> bool:
    """Whether ``candidate``'s held-out error is within ``standard_errors`` standard errors of ``best``'s.

    The standard error of the summed fold-by-fold differences, √K·sd(d). Fold errors that agree to
    ``RANK_DIGITS`` significant digits are a tie, and a tie is within.
    """
    if np.allclose(candidate.fold_sse, best.fold_sse, rtol=10.0**-RANK_DIGITS, atol=0.0):
        return True
    difference = np.subtract(candidate.fold_sse, best.fold_sse)
    if len(difference) < 2:
        return bool(difference.sum() <= 0.0)
    return bool(difference.sum() <= standard_errors * np.sqrt(len(difference)) * np.std(difference, ddof=1))


def rank_candidates(
    target: np.ndarray,
    features: list[Feature],
    compute,
    scorer: HeldOutScorer,
    inputs: np.ndarray | None = None,
    own_inputs: set[str] = frozenset(),
) -> list[Candidate]:
    """Score every candidate as one more regressor of the model's own design; best first.

    Parameters
    ----------
    target : ndarray
        The measured error, all runs stacked.
    compute : callable
        ``compute(feature) -> ndarray``: the candidate's values on the same samples.
    scorer : HeldOutScorer
        The model's regressors on the same samples (each group's inputs in
        its own columns, see :func:`groupfit.heldout.design.group_design`)
        fitted on each held-out fold's complement. Scoring the error rather
        than the in-sample residual matters: a model fitted on the same run
        absorbs part of a missing effect into its coefficients, and only an
        out-of-sample comparison of the model with and without the
        candidate shows it.
    inputs : ndarray, optional
        The model's inputs on the same samples, for the collinearity of each candidate.
    own_inputs : set of str
        The model's input columns: their transforms are marked ``own_input``.
    """
    ranked = []
    for feature in features:
        values = compute(feature)
        if np.ptp(values) == 0.0:
            continue
        ranked.append(
            score_candidate(
                feature,
                values,
                scorer,
                own_input=feature.column in own_inputs,
                collinearity=largest_correlation(values, inputs),
            )
        )
    ranked.sort(key=lambda c: -c.rank)
    return ranked


def score_candidate(
    feature: Feature, values: np.ndarray, scorer: HeldOutScorer, *, own_input: bool = False, collinearity: float = 0.0
) -> Candidate:
    """``values`` (one per sample of the scorer's target) scored as one more regressor: a :class:`Candidate`."""
    return candidate_of_fold_sse(
        feature,
        scorer.fold_sse(values),
        scorer,
        scorer.coefficient(values),
        own_input=own_input,
        collinearity=collinearity,
    )


def candidate_of_fold_sse(
    feature: Feature,
    sse: np.ndarray,
    scorer: HeldOutScorer,
    coefficient: float = 0.0,
    *,
    own_input: bool = False,
    collinearity: float = 0.0,
) -> Candidate:
    """A :class:`Candidate` whose held-out SSE per fold is ``sse``, scored against the scorer's own design."""
    without, with_feature = float(scorer.base_sse.sum()), float(np.sum(sse))
    return Candidate(
        feature=feature,
        score=1.0 - with_feature / without if without > 0 else 0.0,
        coefficient=coefficient,
        explained_rms_um=float(np.sqrt(max(0.0, without - with_feature) / scorer.n_scored)),
        fold_sse=tuple(float(v) for v in sse),
        fold_ratios=tuple(float(r) for r in sse / np.where(scorer.base_sse > 0, scorer.base_sse, 1.0)),
        own_input=own_input,
        collinearity=collinearity,
    )


def largest_correlation(values: np.ndarray, inputs: np.ndarray | None) -> float:
    """Largest |r| between ``values`` and a column of ``inputs`` (0 without inputs)."""
    if inputs is None or inputs.shape[1] == 0:
        return 0.0
    centred = inputs - inputs.mean(axis=0)
    v = values - values.mean()
    norms = np.linalg.norm(centred, axis=0) * np.linalg.norm(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.abs(centred.T @ v) / norms
    return float(np.nanmax(np.where(norms > 0, r, 0.0)))
