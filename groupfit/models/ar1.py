"""The physics first-order autoregressive model of spindle elongation.

Du et al. (J. Harbin Inst. Technol. 53(7), 2021) model the spindle as a rod
heated at one end and cooled by convection; its elongation obeys exactly

    E(k) = C1·E(k−1) + C2(q_k),    C1 = e^{−bΔτ},  C2(q) ∝ q,

where ``q_k`` is the heat input during the sampling interval that ends at
sample k, and C2(0) = 0. An optional *structural* term ``g·(T_s(k) − T_s(0))``
adds the expansion of a part that follows a sensor directly (the bed in the
paper, ``g = α·L``); the recursion then runs on the remainder.

C1 and one C2 per distinct non-zero heat level of the modelling run are fitted
by least squares on one-step-ahead equations, or (``fit_method="free_run"``)
by minimising the free-run error itself, starting from the one-step values.
Predictions *free-run*: each step starts from the model's own previous
prediction, not the measured error, as the model would on a machine; the
first sample is the measured error (``start="measured"``) or 0 (``"zero"``,
the paper's ΔL(0) = 0).
A heat level not seen in the modelling run gets C2 scaled from the nearest
fitted level, either by the heat law ``(q/q_ref)^exponent`` or by a given
ratio of early temperature rise (the paper's rule).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import lfilter
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_array, check_is_fitted

from groupfit.errors import InputError
from groupfit.metrics import ljung_box
from groupfit.setting_levels import setting_levels
from groupfit.settings import AR1_FIT_METHODS, AR1_SCALINGS, AR1_STARTS

MIN_LEVEL_STEPS = 10
"""A heat level held for fewer steps of the modelling run gets no C2 of its own (:func:`level_columns`)."""
REST_FRACTION = 0.01
"""A heat level below this share of the run's largest is rest (C2 = 0), not a level of its own: a tachometer that
reads a few tenths of an r/min at standstill. By the heat law such a level carries at most 1 % of the largest
level's heat (0.05 % with the exponent 5/3), and a C2 fitted to it would carry the noise of the rest instead."""


def closed_form_coefficients(
    flux_W_m2: float,
    *,
    convection_W_m2K: float,
    radius_m: float,
    density_kg_m3: float,
    heat_capacity_J_kgK: float,
    expansion_1_K: float,
    period_s: float,
) -> tuple[float, float]:
    """C1 and C2 (µm) of a rod heated at one end by ``flux_W_m2`` (Du et al., eq. 13–14).

    ``b = 2h/(ρcR)``, ``C1 = e^{−bΔτ}``, ``C2(q) = q·α/(ρcb)·(1 − e^{−bΔτ})``.
    """
    values = dict(
        convection_W_m2K=convection_W_m2K,
        radius_m=radius_m,
        density_kg_m3=density_kg_m3,
        heat_capacity_J_kgK=heat_capacity_J_kgK,
        period_s=period_s,
    )
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"AR(1) closed form: {name} = {value!r}; give a positive number")
    b = 2.0 * convection_W_m2K / (density_kg_m3 * heat_capacity_J_kgK * radius_m)
    c1 = math.exp(-b * period_s)
    c2 = flux_W_m2 * expansion_1_K / (density_kg_m3 * heat_capacity_J_kgK * b) * (1.0 - c1)
    return c1, 1e6 * c2


def free_run(c1: float, inputs: np.ndarray, initial: float) -> np.ndarray:
    """``E(0) = initial``, ``E(k) = c1·E(k−1) + inputs[k]``: the free run, as one linear filter."""
    drive = np.asarray(inputs, dtype=float).copy()
    drive[0] = initial
    return lfilter([1.0], [1.0, -c1], drive)


def early_rise(temperature: np.ndarray, period_s: float, window_s: float = 6000.0) -> float:
    """Temperature rise of a sensor over the first ``window_s`` seconds of a run (100 min by default)."""
    temperature = np.asarray(temperature, dtype=float)
    steps = int(round(window_s / period_s))
    if steps < 1 or steps >= len(temperature):
        raise InputError(f"early-rise window {window_s:g} s does not fit a run of {len(temperature)} samples")
    return float(temperature[steps] - temperature[0])


def level_columns(heat: np.ndarray, exponent: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The fitted heat levels and the one-step design's heat columns over the steps' set heat ``heat``.

    One column per level held for at least :data:`MIN_LEVEL_STEPS` steps, 1 where the step's heat is that
    level. A level held for fewer steps gets no C2 of its own (it would be fitted from those few equations, their
    noise with it): its steps read the nearest such level's C2 by the heat law, ``(q/level)^exponent`` in that
    level's column, as the model reads a level it never saw. Without an ``exponent`` (the early-rise scaling), or
    when no level is held that long, every level gets a column.
    """
    levels, counts = np.unique(heat[heat != 0], return_counts=True)
    held = levels[counts >= MIN_LEVEL_STEPS]
    if exponent is None or held.size in (0, levels.size):
        return levels, np.column_stack([(heat == level).astype(float) for level in levels])
    columns = np.zeros((len(heat), held.size))
    for level in levels:
        nearest = int(np.argmin(np.abs(held - level)))
        columns[heat == level, nearest] = 1.0 if held[nearest] == level else math.pow(level / held[nearest], exponent)
    return held, columns


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
    fit_method : {"one_step", "free_run"}
        Least squares on the one-step-ahead equations, or on the free-run
        error (:func:`scipy.optimize.least_squares` from the one-step values);
        the free-run fit also fits the structural gain when there is one
        (``structural_gain`` is then its starting value).
    start : {"measured", "zero"}
        Where the free run of the fit (``residuals_``, and the free-run fit
        itself) starts: the first measured error, or 0 (ΔL(0) = 0).

    Attributes
    ----------
    c1_ : float
    c2_ : dict[float, float]
        C2 in µm per sample for each non-zero heat level of the modelling run.
    residuals_ : ndarray
        Free-run residuals on the modelling run.
    one_step_residuals_ : ndarray
        Residuals of the one-step-ahead fit (length n − 1).
    structural_gain_ : float or None
        The structural gain in use: as given, or fitted on the free-run error.
    """

    def __init__(
        self,
        structural_gain: float | None = None,
        scaling: str = "heat_law",
        heat_exponent: float = 5 / 3,
        *,
        fit_method: str = "one_step",
        start: str = "measured",
    ):
        self.structural_gain = structural_gain
        self.scaling = scaling
        self.heat_exponent = heat_exponent
        self.fit_method = fit_method
        self.start = start

    def _split(self, X) -> tuple[np.ndarray, np.ndarray]:
        """The heat column and the structural sensor's rise since the first sample (zeros without the term)."""
        X = check_array(X, ensure_min_samples=2)
        heat = X[:, 0]
        if self.structural_gain is None:
            return heat, np.zeros(len(X))
        if X.shape[1] < 2:
            raise InputError("the structural term needs a second column: the structural sensor's temperature")
        return heat, X[:, 1] - X[0, 1]

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
        for name, value, allowed in (
            ("scaling", self.scaling, AR1_SCALINGS),
            ("fit method", self.fit_method, AR1_FIT_METHODS),
            ("start", self.start, AR1_STARTS),
        ):
            if value not in allowed:
                raise InputError(f"AR(1) {name} {value!r}: choose one of {', '.join(allowed)}")
        heat, rise = self._split(X)
        y = check_array(y, ensure_2d=False).ravel()
        gain = 0.0 if self.structural_gain is None else float(self.structural_gain)
        remainder = y - gain * rise
        set_heat = setting_levels(heat)  # a speed read back with noise: the levels it was set to
        set_heat = np.where(set_heat < REST_FRACTION * np.max(set_heat, initial=0.0), 0.0, set_heat)
        if not np.any(set_heat[1:] != 0):
            raise InputError("the modelling run has no heat input (all heat levels are 0): AR(1) cannot be fitted")
        exponent = self.heat_exponent if self.scaling == "heat_law" else None
        levels, columns = level_columns(set_heat[1:], exponent)
        design = np.column_stack([remainder[:-1], columns])
        coef, *_ = np.linalg.lstsq(design, remainder[1:], rcond=None)
        initial = remainder[0] if self.start == "measured" else 0.0
        if self.fit_method == "free_run":
            indicators = design[:, 1:]
            structural = self.structural_gain is not None

            def free_run_error(params):
                inputs = np.concatenate([[0.0], indicators @ params[1 : 1 + len(levels)]])
                g = params[-1] if structural else 0.0
                return free_run(params[0], inputs, initial) + g * rise - y

            start = np.concatenate([coef, [gain]]) if structural else coef
            lower = [0.0] + [-np.inf] * (len(start) - 1)
            params = least_squares(free_run_error, start, bounds=(lower, np.inf)).x
            coef = params[: 1 + len(levels)]
            if structural:
                gain = float(params[-1])
                remainder = y - gain * rise
                design[:, 0] = remainder[:-1]
        self.structural_gain_ = None if self.structural_gain is None else gain
        self.c1_ = float(coef[0])
        self.c2_ = {float(level): float(c) for level, c in zip(levels, coef[1:])}
        self.one_step_residuals_ = remainder[1:] - design @ coef
        self.n_features_in_ = np.asarray(X).shape[1]
        self.residuals_ = y - self.predict(X, initial_error=y[0] if self.start == "measured" else 0.0)
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
        return self.c2_[reference] * math.pow(level / reference, self.heat_exponent)

    def predict(
        self, X, initial_error: float = 0.0, rise_ratio: float | None = None, held: np.ndarray | None = None
    ) -> np.ndarray:
        """Free-run prediction from ``initial_error`` at the first sample; where ``held`` (a heat reading the
        AR(1) routine does not take, :mod:`groupfit.ar1.rule`) the recursion's state is held, not stepped."""
        check_is_fitted(self, "c1_")
        heat, rise = self._split(X)
        hold = np.zeros(len(heat), dtype=bool) if held is None else np.asarray(held, dtype=bool)
        structural = rise * (self.structural_gain_ or 0.0)
        inputs = np.array([0.0 if skip else self.c2_for(level, rise_ratio) for level, skip in zip(heat, hold)])
        remainder = np.empty(len(heat))
        remainder[0] = initial_error - structural[0]
        for k in range(1, len(heat)):
            remainder[k] = remainder[k - 1] if hold[k] else self.c1_ * remainder[k - 1] + inputs[k]
        return remainder + structural

    def ljung_box(self, lags: int = 10) -> dict[str, float]:
        """Ljung–Box whiteness test of the one-step residuals (:func:`groupfit.metrics.ljung_box`)."""
        check_is_fitted(self, "one_step_residuals_")
        return ljung_box(self.one_step_residuals_, lags)
