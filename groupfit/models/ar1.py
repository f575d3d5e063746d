"""The physics first-order autoregressive model of spindle elongation.

Du et al. (J. Harbin Inst. Technol. 53(7), 2021) model the spindle as a rod
heated at one end and cooled by convection; its elongation obeys exactly

    E(k) = C1·E(k−1) + C2(q_k),    C1 = e^{−bΔτ},  C2(q) ∝ q,

where ``q_k`` is the heat input during the sampling interval that ends at
sample k, and C2(0) = 0. An optional *structural* term ``g·(T_s(k) − T_s(0))``
adds the expansion of a part that follows a sensor directly (the bed in the
paper, ``g = α·L``); the recursion then runs on the remainder.

C1 and one C2 per distinct non-zero heat level of the modelling run are fitted
by least squares on one-step-ahead equations. Predictions *free-run*: each
step starts from the model's own previous prediction, not the measured error,
as the model would on a machine; only the first sample is taken as measured.
A heat level not seen in the modelling run gets C2 scaled from the nearest
fitted level, either by the heat law ``(q/q_ref)^exponent`` or by a given
ratio of early temperature rise (the paper's rule).
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_array, check_is_fitted

from groupfit.errors import InputError
from groupfit.metrics import ljung_box

SCALINGS = ("heat_law", "rise")


def early_rise(temperature: np.ndarray, period_s: float, window_s: float = 6000.0) -> float:
    """Temperature rise of a sensor over the first ``window_s`` seconds of a run (100 min by default)."""
    temperature = np.asarray(temperature, dtype=float)
    steps = int(round(window_s / period_s))
    if steps < 1 or steps >= len(temperature):
        raise InputError(f"early-rise window {window_s:g} s does not fit a run of {len(temperature)} samples")
    return float(temperature[steps] - temperature[0])


class AR1Model(RegressorMixin, BaseEstimator):
    """First-order autoregressive thermal-error model with heat-dependent input.

    Parameters
    ----------
    structural_gain : float or None
        µm per K of the structural term on the second column of X (e.g.
        ``α·L``); None for no structural term.
    scaling : {"heat_law", "rise"}
        How C2 is obtained for a heat level the modelling run did not have.
    heat_exponent : float
        Exponent of the heat law: C2 ∝ q^exponent (5/3 for bearing heat
        against speed, 1 for a heat flux).

    Attributes
    ----------
    c1_ : float
    c2_ : dict[float, float]
        C2 in µm per sample for each non-zero heat level of the modelling run.
    residuals_ : ndarray
        Free-run residuals on the modelling run.
    one_step_residuals_ : ndarray
        Residuals of the one-step-ahead fit (length n − 1).
    """

    def __init__(self, structural_gain: float | None = None, scaling: str = "heat_law", heat_exponent: float = 5 / 3):
        self.structural_gain = structural_gain
        self.scaling = scaling
        self.heat_exponent = heat_exponent

    def _split(self, X) -> tuple[np.ndarray, np.ndarray]:
        X = check_array(X, ensure_min_samples=2)
        heat = X[:, 0]
        if self.structural_gain is None:
            structural = np.zeros(len(X))
        else:
            if X.shape[1] < 2:
                raise InputError("the structural term needs a second column: the structural sensor's temperature")
            structural = self.structural_gain * (X[:, 1] - X[0, 1])
        return heat, structural

    def fit(self, X, y):
        """Fit C1 and C2 per heat level.

        Parameters
        ----------
        X : array-like, shape (n_samples, 1 or 2)
            Column 0: heat level during the interval ending at each sample
            (speed in r/min, heat flux, power); column 1: the structural
            sensor's temperature when ``structural_gain`` is set.
        y : array-like, shape (n_samples,)
            Thermal error in µm.
        """
        if self.scaling not in SCALINGS:
            raise InputError(f"AR(1) scaling {self.scaling!r}: choose one of {', '.join(SCALINGS)}")
        heat, structural = self._split(X)
        y = check_array(y, ensure_2d=False).ravel()
        remainder = y - structural
        levels = np.unique(heat[1:][heat[1:] != 0])
        if levels.size == 0:
            raise InputError("the modelling run has no heat input (all heat levels are 0): AR(1) cannot be fitted")
        design = np.column_stack([remainder[:-1]] + [(heat[1:] == level).astype(float) for level in levels])
        coef, *_ = np.linalg.lstsq(design, remainder[1:], rcond=None)
        self.c1_ = float(coef[0])
        self.c2_ = {float(level): float(c) for level, c in zip(levels, coef[1:])}
        self.one_step_residuals_ = remainder[1:] - design @ coef
        self.n_features_in_ = np.asarray(X).shape[1]
        self.residuals_ = y - self.predict(X, initial_error=y[0])
        return self

    def c2_for(self, level: float, rise_ratio: float | None = None) -> float:
        """C2 for a heat level: fitted, or scaled from the nearest fitted level."""
        check_is_fitted(self, "c2_")
        level = float(level)
        if level == 0.0:
            return 0.0
        if level in self.c2_:
            return self.c2_[level]
        reference = min(self.c2_, key=lambda fitted: abs(fitted - level))
        if self.scaling == "rise":
            if rise_ratio is None:
                raise InputError(
                    f"heat level {level:g} was not in the modelling run: give the early-rise ratio "
                    "or use the heat-law scaling"
                )
            return self.c2_[reference] * rise_ratio
        return self.c2_[reference] * (level / reference) ** self.heat_exponent

    def predict(self, X, initial_error: float = 0.0, rise_ratio: float | None = None) -> np.ndarray:
        """Free-run prediction from ``initial_error`` at the first sample."""
        check_is_fitted(self, "c1_")
        heat, structural = self._split(X)
        inputs = np.array([self.c2_for(level, rise_ratio) for level in heat])
        remainder = np.empty(len(heat))
        remainder[0] = initial_error - structural[0]
        for k in range(1, len(heat)):
            remainder[k] = self.c1_ * remainder[k - 1] + inputs[k]
        return remainder + structural

    def ljung_box(self, lags: int = 10) -> dict[str, float]:
        """Ljung–Box whiteness test of the one-step residuals (:func:`groupfit.metrics.ljung_box`)."""
        check_is_fitted(self, "one_step_residuals_")
        return ljung_box(self.one_step_residuals_, lags)
