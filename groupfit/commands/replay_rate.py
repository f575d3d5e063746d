"""Where the rate limit held the compensation away from its target after the run had started.

The residual ``replay`` scores is the error less the compensation's target
(within the clamps): the rate limit shapes how the output reaches it, from 0
at power-on. Once the output has reached its target, it lags only when the
target jumps: when a sensor fault ends (the prediction comes back from 0) or a
check moves the correction by more than the rate allows. There the machine
keeps an error the score does not show, and the report says how much.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from groupfit.runtime import FAULT_SENSOR

LAG_TOLERANCE_UM = 0.01
"""A compensation this close to its target (µm) has reached it."""


def rate_check(error: np.ndarray | None, replay) -> tuple[dict[str, Any], list[str]]:
    """The samples (measured, not in sensor fault) after the output first reached its target where the rate
    limit held it more than :data:`LAG_TOLERANCE_UM` from it, the largest lag, and the RMS of the error the
    output as served leaves; and a note. Nothing when there is none."""
    if replay.target_um is None:
        return {}, []
    lag = np.asarray(replay.compensation_um, dtype=float) - np.asarray(replay.target_um, dtype=float)
    reached = np.flatnonzero(np.abs(lag) <= LAG_TOLERANCE_UM)
    if not reached.size:
        return {}, []
    live = (np.asarray(replay.fault) & FAULT_SENSOR) == 0
    after = np.arange(lag.size) > reached[0]
    lagging = after & live & (np.abs(lag) > LAG_TOLERANCE_UM)
    if not lagging.any():
        return {}, []
    found: dict[str, Any] = {"samples": int(lagging.sum()), "largest_lag_um": float(np.max(np.abs(lag[lagging])))}
    note = (
        f"the rate limit held the compensation away from its target on {found['samples']} sample(s) after it had "
        f"reached it (after a sensor fault, or a check that moved the correction by more than the rate), by up "
        f"to {found['largest_lag_um']:.3g} µm; the residual and RMS count the target"
    )
    if error is not None:
        served = np.asarray(error, dtype=float) + np.asarray(replay.compensation_um, dtype=float)
        scored = served[live & np.isfinite(served)]
        if scored.size:
            found["rms_as_served_um"] = float(np.sqrt(np.mean(scored**2)))
            note += f"; the output as served leaves {found['rms_as_served_um']:.4g} µm RMS"
    return {"rate_limited": found}, [note]


__all__ = ["LAG_TOLERANCE_UM", "rate_check"]
