"""The JSON runtime table's ``recalibration`` object: the probe-check filter's numbers and steps in words.

Every table carries it (a model without a ``recalibration`` section: the
default hold of :mod:`groupfit.runtime.recalibration`). The format is not
raised for it: a runtime that ignores the object computes exactly what
``groupfit replay`` computes without checks, since the correction stays 0
until a check is applied; one that takes checks performs these steps too.
"""

from __future__ import annotations

from groupfit.runtime import PROBE_APPLIED, PROBE_IGNORED, PROBE_REJECTED, RuleTables
from groupfit.runtime.recalibration import PROBE_LIMIT_UM

PROBE_STEPS = (
    "every sample, after the derived inputs and the switching, before the prediction (faults included): "
    "x[0] = x[0] + x[1]; x[1] = phi * x[1]; for j in 0..2: A[0][j] = P[0][j] + P[1][j], A[1][j] = phi * P[1][j], "
    "A[2][j] = P[2][j]; then for i in 0..2: P[i][0] = A[i][0] + A[i][1], P[i][1] = A[i][1] * phi, "
    "P[i][2] = A[i][2], P[i][i] = P[i][i] + q[i]; then clamp every x[i] to [-x_max[i], x_max[i]] (upper first). "
    "x starts at 0, P at diag(p0), applied, model and command at 0, usable false, rejected 0, significant false, "
    "gap2 0",
    "at a sample where the group advanced and the sample before computed a prediction (it was not in a sensor "
    "fault): g = that prediction (the transfer's share included, the probe correction not) - the new group's "
    "prediction at this sample (position terms included, before any share); gap2 = gap2 + g * g",
    "under a sensor fault: usable = false (prediction and target 0 as before; applied unchanged)",
    "otherwise, after target = -prediction (and the dead band): command = -target; target = min(max(target, "
    "clamp_low), clamp_high) (the model's clamp, upper bound first; clamp_low and clamp_high start at "
    "comp_min_um and comp_max_um); model = -target; usable = not held; "
    "t = x[0] + x[2] * model, then t = 0 if significance2 > 0 and not significant; "
    "delta = t - applied limited to [-rate_um, rate_um]; applied = applied + delta; "
    "prediction = prediction + applied; target = target - applied; then target = min(max(target, "
    "output_min_um), output_max_um) (the checks may carry the output beyond the model's clamp by x_max[0]) and "
    "the rate limit as before",
    "a probe check z (the measured thermal error, um) after a sample: ignored if not usable or not "
    "(-probe_limit_um <= z <= probe_limit_um); nu = (z - model) - (x[0] + x[2] * model); for i in 0..2: "
    "Ph[i] = P[i][0] + P[i][2] * model, hP[i] = P[0][i] + P[2][i] * model; S = hP[0] + hP[2] * model + r; "
    "ignored unless S > 0; G = S + gap2, G = p0[0] if G < p0[0], then gap2 = 0; "
    "if nu * nu > gate2 * G: if rejected < confirm_after: rejected += 1, rejected "
    "(nothing else changes), else (the checks keep disagreeing: a real change) rejected = 0, x[0] = x[0] + nu, "
    "P = diag(p0), clamp x as below, significant = true: applied; otherwise rejected = 0, K[i] = Ph[i] / S, "
    "x[i] = x[i] + K[i] * nu, P[i][j] = P[i][j] - K[i] * hP[j] for all i, j, clamp x (as in the time update), "
    "then with the new P: t = x[0] + x[2] * model, hP[i] = P[0][i] + P[2][i] * model, "
    "significant = t * t > significance2 * (hP[0] + hP[2] * model): applied",
    "after an applied check z: w = 2 * |z| (w = |z|, then w = w + w); if w > clamp_high: clamp_high = "
    "min(w, output_max_um); if -w < clamp_low: clamp_low = max(-w, output_min_um); then the model's command "
    "under the widened clamp: w = -command, w = min(max(w, clamp_low), clamp_high) (upper bound first), "
    "w = -w; if w != model: x[0] = x[0] + (1 + x[2]) * (model - w), clamp x (as in the time update), "
    "model = w, significant = true",
)


def with_recalibration(table: dict, tables: RuleTables) -> dict:
    """The table with its ``recalibration`` object."""
    t = tables.recalibration
    table["recalibration"] = {
        "method": t.method,
        "terms": list(t.terms),
        "note": "states x = (offset um, drift um per sample, gain); q: process variance per sample; p0: initial "
        "variance; phi: drift decay per sample; r: variance of one check (um^2); gate2: squared innovation gate; "
        "significance2: squared significance a correction needs to be applied (0: always applied); "
        "x_max: bounds of x; rate_um: largest move of the applied correction per sample. A check follows its "
        "sample's step (docs/recalibration.md)",
        "q": list(t.q),
        "p0": list(t.p0),
        "phi": t.phi,
        "r": t.r,
        "gate2": t.gate2,
        "significance2": t.significance2,
        "confirm_after": t.confirm_after,
        "x_max": list(t.x_max),
        "rate_um": t.rate_um,
        "output_min_um": tables.output_min_um,
        "output_max_um": tables.output_max_um,
        "probe_limit_um": PROBE_LIMIT_UM,
        "codes": {"applied": PROBE_APPLIED, "rejected": PROBE_REJECTED, "ignored": PROBE_IGNORED},
        "steps": list(PROBE_STEPS),
    }
    return table


__all__ = ["PROBE_STEPS", "with_recalibration"]
