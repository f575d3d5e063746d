"""Identification of the ball-screw model, step by step as in seed 003 §2.3.

1. h and (C1, C2) of the first source from the steady profile (eq. 5): for a
   given λ the profile is linear in C1 and C2, so λ is found by a bounded
   one-dimensional search over the residual of that linear fit (variable
   projection), and h = λ²·k·R0/2.
2. α′(t) at times every ``alpha_step_s`` from the transient at the sensors
   other than the reference (eq. 7 with h, C1, C2 fixed): one α′ per time,
   the source offset x0 shared by all times; a sparse least-squares problem.
3. α′(τ0) = a0 + a1·τ0 by a linear fit of α′(t) against the reference rise
   τ0(t) at those times, over the transient (τ0 below ``transient_fraction``
   of its steady value).
4. For a new source: C1 and C2 by linear least squares on the first t_r
   seconds of two sensors (the reference and the farthest), h, α′ and x0
   kept.

The α′(t) table of step 2 is also kept as a law of its own (the *table* law,
:func:`alpha_curve`): α′ at every sample of the first t_r seconds and every
``alpha_step_s`` after, from all sensors with x0 fixed, interpolated in log t.
A conductor whose properties do not change with temperature heats along the
same normalised transient at any power, so α′(t) carries from one source to
another, where a straight line in τ0 gives a weaker source a smaller α′ at the
same time.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.optimize import least_squares, minimize_scalar
from scipy.sparse import lil_matrix

from groupfit.errors import InputError

from .physics import steady_profile, transient_factor

LAMBDA_BOUNDS = (0.05, 200.0)  # 1/m
ALPHA_BOUNDS = (1e-8, 1e-2)  # m²/s
CURVE_ALPHA_BOUNDS = (1e-8, 1.0)
"""α′ (m²/s) searched for the table law; near the steady state only a large α′ brings the erf factor to 1."""
OFFSET_BOUNDS = (0.0, 0.5)  # m
STEADY_DRIFT = 0.01
"""Largest relative change of the reference rise between the last two steady windows."""


def smooth(rises: np.ndarray, time: np.ndarray, width_s: float) -> np.ndarray:
    """Centred moving average over ``width_s`` seconds (the paper's filtering)."""
    period = float(np.median(np.diff(time)))
    size = int(round(width_s / period))
    return uniform_filter1d(rises, size=size, axis=0, mode="nearest") if size > 1 else rises


def on_step(time: np.ndarray, step_s: float) -> np.ndarray:
    """Samples at multiples of ``step_s`` (to half a sampling period)."""
    period = float(np.median(np.diff(time)))
    return np.abs(np.mod(time + 1e-9, step_s)) < period / 2 + 1e-9


def fit_steady_profile(profile: np.ndarray, positions: np.ndarray) -> tuple[float, float, float, float]:
    """λ, C1, C2 and the rms residual (K) of the steady profile (eq. 5)."""

    def linear(lam):
        design = np.column_stack([np.exp(-lam * positions), np.exp(lam * positions)])
        coef, *_ = np.linalg.lstsq(design, profile, rcond=None)
        return coef, float(np.sum((design @ coef - profile) ** 2))

    log_lo, log_hi = np.log(LAMBDA_BOUNDS)
    grid = np.linspace(log_lo, log_hi, 200)
    costs = [linear(np.exp(g))[1] for g in grid]
    best = int(np.argmin(costs))
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
    result = minimize_scalar(
        lambda g: linear(np.exp(g))[1], bounds=(lo, hi), method="bounded", options={"xatol": 1e-10}
    )
    lam = float(np.exp(result.x))
    (c1, c2), cost = linear(lam)
    return lam, float(c1), float(c2), float(np.sqrt(cost / len(profile)))


def identify_first_source(
    rises,
    time,
    positions,
    *,
    conductivity,
    radius,
    source_offset,
    transient_fraction,
    alpha_step_s,
    smooth_s,
    steady_window_s,
    min_sensors,
    dense_until_s,
    label,
) -> dict:
    """Steps 1–3 on the identification run; see the module docstring.

    Raises
    ------
    InputError
        Too few sensors, a run too short or not settled, no heating.
    """
    k = len(positions)
    if k < min_sensors:
        raise InputError(
            f"{label}: {k} temperature sensor(s); identifying h, C1 and C2 from the steady profile "
            f"needs at least {min_sensors} along the screw (the paper uses 8)"
        )
    period = float(np.median(np.diff(time)))
    window = max(int(round(steady_window_s / period)), 1)
    if len(time) < 3 * window or time[-1] < 3 * steady_window_s:
        raise InputError(
            f"{label}: the run lasts {time[-1]:g} s; identifying h needs a run that reaches its steady "
            f"temperature profile (the paper heats for 2 h), at least {3 * steady_window_s:g} s"
        )
    data = smooth(rises, time, smooth_s)
    last, before = data[-window:].mean(axis=0), data[-2 * window : -window].mean(axis=0)
    if last[0] <= 0.5:
        raise InputError(f"{label}: the reference sensor rises by {last[0]:.3g} K only; is the source on?")
    drift = abs(last[0] - before[0]) / last[0]
    if drift > STEADY_DRIFT:
        raise InputError(
            f"{label}: the run has not reached a steady temperature profile (the rise at the source "
            f"still changes by {100 * drift:.1f} % over its last {steady_window_s:g} s); heat longer (the paper: 2 h)"
        )
    lam, c1, c2, steady_rms = fit_steady_profile(last, positions)
    tau_inf = float(steady_profile(positions[0], c1, c2, lam))

    times_idx = np.flatnonzero((time >= alpha_step_s - 1e-9) & on_step(time, alpha_step_s))
    tau0 = data[times_idx, 0]
    used = tau0 <= transient_fraction * tau_inf
    if used.sum() < 2:
        raise InputError(
            f"{label}: fewer than two times with α′ in the transient (t ≥ {alpha_step_s:g} s and the source "
            f"rise below {100 * transient_fraction:g} % of its steady value); raise --transient-fraction (now "
            f"{transient_fraction:g}, default 0.8), or identify on a run that stays in the transient longer"
        )
    alpha, offset, transient_rms = _alpha_table(
        data[times_idx][:, 1:], time[times_idx], positions[1:], c1, c2, lam, source_offset, used
    )
    well = used & (alpha < 0.5 * ALPHA_BOUNDS[1])
    if well.sum() < 2:
        raise InputError(f"{label}: α′ could not be identified on the transient; check the run")
    a1, a0 = np.polyfit(tau0[well], alpha[well], 1)
    table = [
        {"t_s": float(t), "alpha_prime_m2_s": float(a), "tau0_K": float(tau), "used": bool(w)}
        for t, a, tau, w in zip(time[times_idx], alpha, tau0, well)
    ]
    curve = alpha_curve(data, time, positions, c1, c2, lam, offset, dense_until_s=dense_until_s, step_s=alpha_step_s)
    return {
        "lambda": lam,
        "C1": c1,
        "C2": c2,
        "alpha_law": (float(a0), float(a1)),
        "alpha_curve": curve,
        "alpha_table": table,
        "source_offset": float(offset),
        "residuals": {
            "steady_rms_K": steady_rms,
            "transient_rms_K": transient_rms,
            "steady_rise_at_reference_K": tau_inf,
            "steady_drift": float(drift),
        },
    }


def alpha_curve(rises, time, positions, c1, c2, lam, source_offset, *, dense_until_s, step_s):
    """α′ (m²/s) at every sample with 0 < t ≤ ``dense_until_s`` and every ``step_s`` after, one scalar fit per time.

    All sensors enter, the reference included: in the first seconds it is the
    only one the heat has reached. Each α′ minimises the squared error of eq. 7
    over the sensors (h, C1, C2 and x0 fixed): a log grid, then a bounded
    search around its best point.

    Returns
    -------
    times, alphas : ndarray
    """
    rows = np.flatnonzero((time > 0) & ((time <= dense_until_s + 1e-9) | on_step(time, step_s)))
    steady = steady_profile(positions, c1, c2, lam)
    log_lo, log_hi = np.log(CURVE_ALPHA_BOUNDS)
    grid = np.linspace(log_lo, log_hi, 161)

    def cost(log_alpha, row):
        model = steady * transient_factor(positions, time[row], np.exp(log_alpha), source_offset)
        return float(np.sum((model - rises[row]) ** 2))

    factor = transient_factor(
        positions[None, None, :], time[rows][:, None, None], np.exp(grid)[None, :, None], source_offset
    )
    costs = np.sum((steady * factor - rises[rows][:, None, :]) ** 2, axis=2)
    alphas = np.empty(len(rows))
    for i, (row, best) in enumerate(zip(rows, np.argmin(costs, axis=1))):
        lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
        found = minimize_scalar(cost, bounds=(lo, hi), args=(row,), method="bounded", options={"xatol": 1e-6})
        alphas[i] = np.exp(found.x if found.fun <= costs[i, best] else grid[best])
    return time[rows].astype(float), alphas


def _alpha_table(rises, time, positions, c1, c2, lam, source_offset, used):
    """α′ at each time (one parameter per time) and the shared offset x0.

    x0 is fitted on the transient times only (``used``); the table is then
    completed at every time with x0 fixed.
    """
    steady = steady_profile(positions, c1, c2, lam)
    n_t, n_s = rises.shape

    def solve(rows, offset):
        m = len(rows)
        fit_offset = offset is None

        def residual(p):
            alpha = np.exp(p[:m])
            x0 = p[m] if fit_offset else offset
            model = steady[None, :] * transient_factor(positions[None, :], time[rows][:, None], alpha[:, None], x0)
            return (model - rises[rows]).ravel()

        sparsity = lil_matrix((m * n_s, m + int(fit_offset)))
        for j in range(m):
            sparsity[j * n_s : (j + 1) * n_s, j] = 1
        if fit_offset:
            sparsity[:, m] = 1
        lo = [np.log(ALPHA_BOUNDS[0])] * m + ([OFFSET_BOUNDS[0]] if fit_offset else [])
        hi = [np.log(ALPHA_BOUNDS[1])] * m + ([OFFSET_BOUNDS[1]] if fit_offset else [])
        start = [np.log(1e-5)] * m + ([0.02] if fit_offset else [])
        result = least_squares(residual, start, bounds=(lo, hi), jac_sparsity=sparsity, x_scale="jac")
        alpha = np.exp(result.x[:m])
        return alpha, (float(result.x[m]) if fit_offset else float(offset)), result.fun

    rows = np.flatnonzero(used)
    if source_offset == "fit":
        _, offset, _ = solve(rows, None)
    else:
        offset = float(source_offset)
    alpha, _, residual = solve(np.arange(n_t), offset)
    transient = residual.reshape(n_t, n_s)[used]
    return alpha, offset, float(np.sqrt(np.mean(transient**2)))


def refit_source(rises, time, positions, alpha, *, lam, source_offset, identification_time_s, label):
    """C1, C2 and the rms residual (K) from the first t_r seconds of the reference and farthest sensors.

    ``alpha`` holds α′ (m²/s) at every sample of the run.
    """
    if len(positions) < 2:
        raise InputError(
            f"{label}: {len(positions)} temperature sensor(s); re-identifying C1 and C2 of a new source needs two "
            "(the paper: 0 and 14 cm from the source)"
        )
    if time[-1] < identification_time_s:
        raise InputError(
            f"{label}: the run lasts {time[-1]:g} s; C1 and C2 of a new source come from its first "
            f"{identification_time_s:g} s (t_r)"
        )
    window = (time > 0) & (time <= identification_time_s + 1e-9)
    if window.sum() < 2:
        raise InputError(f"{label}: fewer than two samples in the first {identification_time_s:g} s")
    columns = [0, len(positions) - 1]
    x = positions[columns]
    factor = transient_factor(x[None, :], time[window][:, None], np.asarray(alpha)[window][:, None], source_offset)
    design = np.stack([np.exp(-lam * x)[None, :] * factor, np.exp(lam * x)[None, :] * factor], axis=-1)
    design = design.reshape(-1, 2)
    target = rises[window][:, columns].reshape(-1)
    coef, *_ = np.linalg.lstsq(design, target, rcond=None)
    rms = float(np.sqrt(np.mean((design @ coef - target) ** 2)))
    return float(coef[0]), float(coef[1]), rms
