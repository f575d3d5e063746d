"""Held-out squared error of a linear design, fold by fold, and of the design with one more regressor.

The scorer behind every "does it hold on the next run?" question of the
project: the diagnosis scores candidate effects with it, ``fit`` checks a model
with it, input selection and the ridge penalty are chosen by it.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import pinvh
from threadpoolctl import threadpool_limits

from groupfit.heldout.folds import Folds
from groupfit.models.ridge import input_spreads


def refined_solution(gram_inverse: np.ndarray, Z: np.ndarray, y: np.ndarray, penalty: np.ndarray) -> np.ndarray:
    """The (penalised) least-squares coefficients of ``y ≈ Z·β`` from the inverse of ``ZᵀZ + diag(penalty)``,
    with one step of iterative refinement.

    The normal equations square the design's condition number: on absolute temperatures (columns far from
    zero beside a constant) the first solution keeps only about nine digits. One correction from the
    residual of the normal equations brings it to what a QR solution of the design itself gives.
    """
    coef = gram_inverse @ (Z.T @ y)
    return coef + gram_inverse @ (Z.T @ (y - Z @ coef) - penalty * coef)


class HeldOutScorer:
    """Held-out squared error of ``target ≈ design·β`` with one more regressor, fold by fold.

    Each fold's fit on the other folds is computed once; a candidate column
    then costs one projection per fold (the Frisch–Waugh–Lovell update of
    the coefficients), not a new least-squares problem. The projections use
    the pseudo-inverse of each fold's Gram matrix of the norm-scaled design,
    so a design that loses rank on a fold (a group absent from it) still has
    a defined, minimum-norm answer.

    With ``ridge_alpha > 0`` (a global model fitted with a ridge penalty,
    :mod:`groupfit.models.ridge`) every fit is the penalised one, the
    candidate penalised like the inputs, the spreads those of all samples:
    the update then solves the penalised normal equations in the same way.
    """

    def __init__(
        self,
        target: np.ndarray,
        design: np.ndarray,
        folds: Folds,
        *,
        ridge_alpha: float = 0.0,
        fit_intercept: bool = True,
    ):
        self.ridge_alpha = float(ridge_alpha)
        self.fit_intercept = fit_intercept
        self.folds = folds
        with threadpool_limits(limits=1, user_api="blas"):  # products this small only lose to thread hand-offs
            self._fit(target, design, folds)

    def _fit(self, target, design, folds) -> None:
        self.target = target
        norms = np.linalg.norm(design, axis=0)
        norms = np.where(norms > 0, norms, 1.0)
        self.design = design / norms
        # the ridge penalty of each column, per training row, on the norm-scaled design
        self.penalty_per_row = (
            self.ridge_alpha * input_spreads(design, fit_intercept=self.fit_intercept) ** 2 / norms**2
        )
        everything = np.ones(len(target), dtype=bool)
        self.splits = [*folds.splits(), (everything, np.zeros_like(everything))]
        self.fits = []
        for train, _ in self.splits:
            Z = self.design[train]
            penalty = self.penalty_per_row * np.count_nonzero(train)
            gram_inverse = pinvh(Z.T @ Z + np.diag(penalty), atol=0.0, rtol=1e-13)
            coef = refined_solution(gram_inverse, Z, target[train], penalty)
            self.fits.append((gram_inverse, coef, target[train] - Z @ coef, penalty))
        self.base_sse = np.array(
            [
                float(np.sum((target[test] - self.design[test] @ coef) ** 2))
                for (_, test), (_, coef, *_) in zip(self.splits[:-1], self.fits[:-1])
            ]
        )
        self.n_scored = max(sum(int(np.count_nonzero(test)) for _, test in self.splits[:-1]), 1)

    def _penalty_per_row(self, values: np.ndarray) -> float:
        """The candidate's ridge penalty per training row: penalised like the inputs (0 for least squares)."""
        if self.ridge_alpha == 0:
            return 0.0
        return self.ridge_alpha * float(input_spreads(values[:, None], fit_intercept=self.fit_intercept)[0]) ** 2

    def _update(self, values: np.ndarray, fold: int, penalty_per_row: float) -> tuple[float, np.ndarray]:
        """Coefficient of ``values`` fitted with the design on the fold's training rows, and its design part."""
        train, _ = self.splits[fold]
        gram_inverse, _, residual, design_penalty = self.fits[fold]
        v_coef = refined_solution(gram_inverse, self.design[train], values[train], design_penalty)
        v_res = values[train] - self.design[train] @ v_coef
        if self.ridge_alpha > 0:  # the penalised normal equations
            denom = float(values[train] @ v_res) + penalty_per_row * np.count_nonzero(train)
            numerator = float(values[train] @ residual)
        else:
            denom = float(v_res @ v_res)
            numerator = float(v_res @ residual)
        if denom <= 1e-12 * max(1.0, float(values[train] @ values[train])):
            return 0.0, v_coef
        return numerator / denom, v_coef

    def fold_sse(self, values: np.ndarray) -> np.ndarray:
        """Held-out SSE per fold with ``values`` as one more regressor."""
        sse = np.empty(len(self.splits) - 1)
        penalty = self._penalty_per_row(values)
        for f, (_, test) in enumerate(self.splits[:-1]):
            gamma, v_coef = self._update(values, f, penalty)
            coef = self.fits[f][1]
            design = self.design[test]
            error = self.target[test] - design @ coef - gamma * (values[test] - design @ v_coef)
            sse[f] = float(error @ error)
        return sse

    def coefficient(self, values: np.ndarray) -> float:
        """The candidate's coefficient fitted with the design on all samples."""
        return self._update(values, len(self.splits) - 1, self._penalty_per_row(values))[0]

    def with_regressor(self, values: np.ndarray) -> "HeldOutScorer":
        """The scorer of the same design with ``values`` as one more regressor, on the same folds."""
        return HeldOutScorer(
            self.target,
            np.column_stack([self.design, values]),
            self.folds,
            ridge_alpha=self.ridge_alpha,
            fit_intercept=self.fit_intercept,
        )

    @property
    def held_out_rms(self) -> float:
        """RMS of the design's own error on the held-out folds (no candidate), µm."""
        return float(np.sqrt(self.base_sse.sum() / self.n_scored))

    @property
    def in_sample_rms(self) -> float:
        """RMS of the design's residual fitted on all samples, µm."""
        return float(np.sqrt(np.mean(self.fits[-1][2] ** 2)))
