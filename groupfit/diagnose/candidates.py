"""Candidate explanations of a residual, and how much of it each explains out of sample.

Candidates are every usable column the model does not use (ambient
temperature, spindle speed, on/off of other heat sources, axis position,
unused sensors), as measured, low-passed over a grid of time constants
(thermal lag), differentiated and delayed, and the same transforms of the
model's own inputs. A column is left out, with the reason, when it is not
numeric, has non-finite values, or is constant (a dead sensor).

The score is the share of the model's error a candidate removes in *blocked
cross-validation in time*: the run is cut into contiguous blocks, and each
block is predicted by the model's own regression (each group's inputs in its
own columns) refitted on the other blocks, with and without the candidate as
one more regressor. A candidate that only fits the stretch of the run it was
fitted on scores near zero or below.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from groupfit.features import Feature

TAUS_S = (600.0, 1200.0, 1800.0, 3600.0, 5400.0, 7200.0, 10800.0, 14400.0, 21600.0, 28800.0)
DELAYS = (1, 3, 10)
N_BLOCKS = 10


@dataclass(frozen=True)
class Candidate:
    feature: Feature
    score: float
    coefficient: float
    explained_rms_um: float
    """RMS (µm) of the residual the candidate removes out of sample: √((SSE_without − SSE_with)/N)."""

    def to_dict(self) -> dict:
        return {
            "column": self.feature.column,
            "transform": self.feature.transform,
            "tau_s": self.feature.tau_s,
            "delay_samples": self.feature.delay_samples or None,
            "name": self.feature.name,
            "description": self.feature.describe(),
            "score": self.score,
            "explained_rms_um": self.explained_rms_um,
        }


def usable_columns(frame: pd.DataFrame, exclude: set[str]) -> tuple[list[str], list[str]]:
    """Columns that can explain a residual, and a note for each one left out."""
    usable, notes = [], []
    for column in frame.columns:
        if column in exclude:
            continue
        values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
        bad = int((~np.isfinite(values)).sum())
        if bad == len(values):
            notes.append(f"column '{column}' left out: not numeric or empty")
        elif bad:
            notes.append(f"column '{column}' left out: {bad} non-finite value(s) (a failing sensor?)")
        elif np.ptp(values) == 0.0:
            notes.append(f"column '{column}' left out: constant {values[0]:g} (a dead sensor?)")
        else:
            usable.append(column)
    return usable, notes


def candidate_features(columns: list[str], model_inputs: list[str]) -> list[Feature]:
    """The transforms tried: measured value (columns only), low-pass, derivative, delay."""
    features = []
    for column in [*columns, *model_inputs]:
        if column in columns:
            features.append(Feature(column))
        features.extend(Feature(column, "lowpass", tau_s=tau) for tau in TAUS_S)
        features.append(Feature(column, "derivative"))
        features.extend(Feature(column, "delay", delay_samples=d) for d in DELAYS)
    return features


def blocked_cv_sse(target: np.ndarray, design: np.ndarray, n_blocks: int = N_BLOCKS) -> float:
    """Squared error of ``target ≈ design·β`` on held-out contiguous blocks of time."""
    edges = np.linspace(0, len(target), n_blocks + 1).astype(int)
    sse = 0.0
    for first, last in zip(edges[:-1], edges[1:]):
        train = np.r_[0:first, last : len(target)]
        coef, *_ = np.linalg.lstsq(design[train], target[train], rcond=None)
        sse += float(np.sum((target[first:last] - design[first:last] @ coef) ** 2))
    return sse


def rank_candidates(
    target: np.ndarray,
    frame: pd.DataFrame,
    features: list[Feature],
    period_s: float,
    design: np.ndarray,
) -> list[Candidate]:
    """Score every candidate as one more regressor of the model's own design; best first.

    Parameters
    ----------
    target : ndarray
        The measured error.
    design : ndarray
        The model's regressors on the same samples, each group's inputs in
        its own columns (see :func:`groupfit.diagnose.loop.group_design`).
        Scoring the error rather than the in-sample residual matters: a
        model fitted on the same run absorbs part of a missing effect into
        its coefficients, and only an out-of-sample comparison of the model
        with and without the candidate shows it.
    """
    rows = np.isfinite(target) & np.isfinite(design).all(axis=1)
    y, Z = target[rows], design[rows]
    without = blocked_cv_sse(y, Z)
    ranked = []
    for feature in features:
        values = feature.compute(frame[feature.column].to_numpy(dtype=float), period_s)[rows]
        if np.ptp(values) == 0.0:
            continue
        augmented = np.column_stack([Z, values])
        coef, *_ = np.linalg.lstsq(augmented, y, rcond=None)
        with_feature = blocked_cv_sse(y, augmented)
        ranked.append(
            Candidate(
                feature=feature,
                score=1.0 - with_feature / without if without > 0 else 0.0,
                coefficient=float(coef[-1]),
                explained_rms_um=float(np.sqrt(max(0.0, without - with_feature) / len(y))),
            )
        )
    ranked.sort(key=lambda c: -c.score)
    return ranked
