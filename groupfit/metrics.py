"""Error metrics of a residual series, in µm."""

from __future__ import annotations

import numpy as np


def error_metrics(residuals: np.ndarray) -> dict[str, float]:
    """R (sum of |e|), RMS and max |e| of a residual series, in µm."""
    residuals = np.asarray(residuals, dtype=float)
    return {
        "R_um": float(np.sum(np.abs(residuals))),
        "rms_um": float(np.sqrt(np.mean(residuals**2))),
        "max_um": float(np.max(np.abs(residuals))),
    }
