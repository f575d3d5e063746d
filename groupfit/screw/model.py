"""The estimator of the analytic ball-screw model of seed 003: identification on a run and prediction.

The formulas (the temperature rise of eq. 7, the thermal error of eq. 9) are in
:mod:`groupfit.screw.physics`, which also says how α′ and x0 are read.
"""

from __future__ import annotations

import numpy as np

from groupfit.errors import InputError

from . import identify
from .physics import ALPHA_FLOOR, ALPHA_LAWS, convection_from_fin_parameter, temperature_rise, thermal_error


class BallScrewModel:
    """Seed 003's ball-screw temperature field and thermal error, identified as the paper does.

    Parameters
    ----------
    alpha_law : {"table", "line"}
        How α′ is predicted. ``"table"``: α′(t), identified at the first
        source's times (every sample of its first t_r seconds, then every
        ``alpha_step_s``), interpolated in log t and held beyond its ends;
        a linear conductor heats along one normalised transient at any power,
        so the table carries to new sources, and no sensor at the source is
        needed to predict. ``"line"``: the paper's α′ = a0 + a1·τ0, τ0 the
        rise measured at the reference sensor. Both are identified either way.
    diameter : float
        Screw diameter 2R0 (m) of the equivalent cylinder (the paper: the pitch diameter).
    conductivity : float
        Thermal conductivity k (W/(m·K)), known (the paper takes it from a handbook).
    expansion : float
        Mean linear expansion coefficient a_m (1/K).
    source_offset : "fit" or float
        x0 (m): ``"fit"`` identifies it with α′ on the identification run;
        a number fixes it (0 is the formula as printed in the paper).
    transient_fraction : float
        α′(t) values enter the linear fit α′(τ0) while τ0 is below this
        fraction of its steady value (the transient; near the steady state α′
        is not determined and grows without bound).
    alpha_step_s : float
        Spacing of the times at which α′(t) is identified (the paper's table: 500 s).
    identification_time_s : float
        t_r: C1 and C2 of a new source come from its first t_r seconds (paper: 400 s).
    smooth_s : float
        Width of the moving average applied to the identification data
        (the paper filters its temperatures before identifying).
    steady_window_s : float
        The steady profile is the mean of the last ``steady_window_s`` of the run.
    min_sensors : int
        Sensors needed on the identification run (three unknowns h, C1, C2).

    Attributes
    ----------
    h_ : float
        Convection coefficient (W/(m²·K)).
    lambda_ : float
        Fin parameter λ (1/m).
    alpha_prime_ : tuple of float
        ``(a0, a1)``: α′ = a0 + a1·τ0, in m²/s and m²/(s·K).
    alpha_table_ : list of dict
        The α′(t) the line is fitted to (sensors other than the reference):
        ``t_s``, ``alpha_prime_m2_s``, ``tau0_K``, ``used``.
    alpha_curve_ : tuple of ndarray
        ``(times_s, alpha_m2_s)``: the table law's α′(t), from all sensors.
    source_offset_ : float
        x0 (m).
    reference_x_ : float
        Position of the reference sensor (the one nearest the source) whose rise is τ0.
    sources_ : dict
        ``{name: {"C1": …, "C2": …, "method": …}}``.
    identification_ : dict
        Residuals of the identification steps (K).
    """

    def __init__(
        self,
        alpha_law: str = "table",
        diameter: float = 0.02,
        conductivity: float = 45.0,
        expansion: float = 11.5e-6,
        source_offset: str | float = "fit",
        transient_fraction: float = 0.8,
        alpha_step_s: float = 100.0,
        identification_time_s: float = 400.0,
        smooth_s: float = 30.0,
        steady_window_s: float = 300.0,
        min_sensors: int = 4,
    ):
        self.alpha_law = alpha_law
        self.diameter = diameter
        self.conductivity = conductivity
        self.expansion = expansion
        self.source_offset = source_offset
        self.transient_fraction = transient_fraction
        self.alpha_step_s = alpha_step_s
        self.identification_time_s = identification_time_s
        self.smooth_s = smooth_s
        self.steady_window_s = steady_window_s
        self.min_sensors = min_sensors

    # ------------------------------------------------------------- fitting
    def fit(self, rises, time, positions, source: str = "H", label: str = "run") -> "BallScrewModel":
        """Identify h, (C1, C2) of ``source`` and α′(τ0) on one heating run.

        Parameters
        ----------
        rises : array, shape (N, k)
            Temperature rises above ambient (K), sensors in order of ``positions``.
        time : array, shape (N,)
            Seconds from the start of heating.
        positions : array, shape (k,)
            Sensor distances from the source (m), increasing; the first is the reference.
        source : str
            Name of the heat source.
        label : str
            The run's name for messages.
        """
        if self.alpha_law not in ALPHA_LAWS:
            raise ValueError(f"alpha_law must be one of {', '.join(ALPHA_LAWS)}, got {self.alpha_law!r}")
        rises, time, positions = _check_arrays(rises, time, positions)
        radius = self.diameter / 2.0
        fit = identify.identify_first_source(
            rises,
            time,
            positions,
            conductivity=self.conductivity,
            radius=radius,
            source_offset=self.source_offset,
            transient_fraction=self.transient_fraction,
            alpha_step_s=self.alpha_step_s,
            smooth_s=self.smooth_s,
            steady_window_s=self.steady_window_s,
            min_sensors=self.min_sensors,
            dense_until_s=self.identification_time_s,
            label=label,
        )
        self.lambda_ = fit["lambda"]
        self.h_ = convection_from_fin_parameter(self.lambda_, self.conductivity, radius)
        self.alpha_prime_ = fit["alpha_law"]
        self.alpha_table_ = fit["alpha_table"]
        self.alpha_curve_ = fit["alpha_curve"]
        self.source_offset_ = fit["source_offset"]
        self.reference_x_ = float(positions[0])
        self.sources_ = {source: {"C1": fit["C1"], "C2": fit["C2"], "method": "steady profile", "run": label}}
        self.identification_ = fit["residuals"]
        return self

    def fit_source(self, rises, time, positions, source: str, label: str = "run") -> tuple[float, float]:
        """Identify C1 and C2 of a new source from the first t_r seconds of two sensors
        (the reference and the farthest), h, the α′ law and x0 kept; store them under ``source``."""
        self._check_fitted()
        rises, time, positions = _check_arrays(rises, time, positions)
        tau0 = self.law_input(rises, positions, label)
        c1, c2, rms = identify.refit_source(
            rises,
            time,
            positions,
            self.alpha_at(time, tau0),
            lam=self.lambda_,
            source_offset=self.source_offset_,
            identification_time_s=self.identification_time_s,
            label=label,
        )
        self.sources_[source] = {
            "C1": c1,
            "C2": c2,
            "method": f"first {self.identification_time_s:g} s",
            "run": label,
            "rms_K": rms,
        }
        return c1, c2

    # ---------------------------------------------------------- prediction
    def alpha(self, tau0) -> np.ndarray:
        """α′(τ0) = a0 + a1·τ0 (m²/s), never below :data:`ALPHA_FLOOR`."""
        self._check_fitted()
        a0, a1 = self.alpha_prime_
        return np.maximum(a0 + a1 * np.asarray(tau0, dtype=float), ALPHA_FLOOR)

    def alpha_at(self, time, tau0=None) -> np.ndarray:
        """α′ (m²/s) at each sample by the model's law: the table at ``time``, or the line at ``tau0``."""
        self._check_fitted()
        if self.alpha_law == "line":
            if tau0 is None:
                raise ValueError("the line law needs tau0, the rise measured at the reference sensor")
            return self.alpha(tau0)
        times, alphas = self.alpha_curve_
        time = np.asarray(time, dtype=float)
        log_t = np.log(np.clip(time, times[0], times[-1]))
        return np.exp(np.interp(log_t, np.log(times), np.log(alphas)))

    def law_input(self, rises, positions, label: str = "run") -> np.ndarray | None:
        """τ0 when the model's α′ law reads it (the line: the rise at the reference sensor); else None."""
        return self.reference_rise(rises, positions, label) if self.alpha_law == "line" else None

    def reference_rise(self, rises, positions, label: str = "run") -> np.ndarray:
        """τ0: the measured rise at the reference sensor's position."""
        positions = np.asarray(positions, dtype=float)
        match = np.flatnonzero(np.abs(positions - self.reference_x_) <= 1e-6)
        if not match.size:
            raise InputError(
                f"{label}: no sensor at the reference position x = {1000 * self.reference_x_:g} mm "
                f"(column T{1000 * self.reference_x_:g}mm); the model's α′ follows the rise measured there"
            )
        return np.asarray(rises, dtype=float)[:, match[0]]

    def predict(self, time, positions, tau0, source: str) -> np.ndarray:
        """Temperature rises Γ (K), shape (len(time), len(positions)); ``tau0`` only for the line law."""
        c1, c2 = self._source(source)
        alpha = self.alpha_at(time, tau0)[:, None]
        time = np.asarray(time, dtype=float)[:, None]
        x = np.asarray(positions, dtype=float)[None, :]
        return temperature_rise(x, time, c1, c2, self.lambda_, alpha, self.source_offset_)

    def predict_error(self, time, x, tau0, source: str) -> np.ndarray:
        """Thermal error E (µm) at position(s) ``x`` (scalar or one per sample)."""
        c1, c2 = self._source(source)
        time = np.asarray(time, dtype=float)
        x = np.broadcast_to(np.asarray(x, dtype=float), time.shape)
        alpha = self.alpha_at(time, tau0)
        return thermal_error(x, time, c1, c2, self.lambda_, alpha, self.expansion, self.source_offset_)

    # ------------------------------------------------------------- helpers
    def _source(self, source: str) -> tuple[float, float]:
        self._check_fitted()
        if source not in self.sources_:
            raise InputError(f"no heat source '{source}' in the model; it has {', '.join(self.sources_)}")
        entry = self.sources_[source]
        return float(entry["C1"]), float(entry["C2"])

    def _check_fitted(self) -> None:
        if not hasattr(self, "lambda_"):
            raise RuntimeError("BallScrewModel is not fitted; call fit first")

    def get_params(self, *, deep: bool = True) -> dict:
        return {
            name: getattr(self, name)
            for name in (
                "alpha_law",
                "diameter",
                "conductivity",
                "expansion",
                "source_offset",
                "transient_fraction",
                "alpha_step_s",
                "identification_time_s",
                "smooth_s",
                "steady_window_s",
                "min_sensors",
            )
        }


def _check_arrays(rises, time, positions):
    rises = np.asarray(rises, dtype=float)
    time = np.asarray(time, dtype=float)
    positions = np.asarray(positions, dtype=float)
    if rises.ndim != 2 or rises.shape != (len(time), len(positions)):
        raise ValueError(f"rises must have shape (len(time), len(positions)), got {rises.shape}")
    if np.any(np.diff(positions) <= 0):
        raise ValueError("positions must be strictly increasing")
    return rises, time, positions
