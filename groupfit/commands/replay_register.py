"""What an integer register (``replay --resolution-um R --counts-limit L``) leaves of the compensation.

The register holds whole counts of ``R`` µm up to ``±L``; a compensation beyond ``L·R`` saturates there. The
replay's ``rms_um`` scores the rule's compensation, as the other targets apply it; this adds the samples the
register saturates on and the RMS of what it applies, with a note when it saturates.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from groupfit.export.sheet import IntegerForm
from groupfit.runtime import Replay


def register_check(counts: IntegerForm | None, residual: np.ndarray | None, replay: Replay) -> tuple[dict, list[str]]:
    """``{"register": {...}}`` (resolution, limit, saturated samples, RMS of the register's compensation) and a
    note when it saturates; nothing without a register. ``residual``: what the rule's compensation leaves, as
    the replay scores it (None without an error column)."""
    if counts is None:
        return {}, []
    target = np.asarray(replay.target_um, dtype=float)
    applied = np.array([counts.um(counts.counts(c)) if np.isfinite(c) else np.nan for c in target])
    saturated = int(np.sum(np.isfinite(target) & (np.abs(target) > counts.range_um)))
    rms = None
    if residual is not None:
        scored = (residual - target + applied)[np.isfinite(residual)]  # the register's value in the target's place
        rms = float(np.sqrt(np.mean(scored**2))) if scored.size else None
    section: dict[str, Any] = {
        "resolution_um": counts.resolution_um,
        "limit_counts": counts.limit,
        "saturated_samples": saturated,
        "rms_um": rms,
    }
    notes = []
    if saturated:
        held = f"; the RMS of what it applies is {rms:.4g} µm" if rms is not None else ""
        notes.append(
            f"the integer register saturates at ±{counts.limit} counts (±{counts.range_um:g} µm) "
            f"on {saturated} of {len(target)} samples{held}; the RMS above scores the compensation the rule "
            "asks for: widen --counts-limit or coarsen --resolution-um"
        )
    return {"register": section}, notes


__all__ = ["register_check"]
