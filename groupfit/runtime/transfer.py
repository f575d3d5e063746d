"""The bumpless transfer of the run-time rule, over whole runs at once.

After a switch from group g to g+1 the rule does not jump from the old
group's prediction to the new one's: for ``B = blend_samples`` samples (the
soft groups' overlap n, where both groups' models hold) it serves
``old + w·(new − old)`` with ``w = k / (B + 1)`` at the switch's k-th sample
(k = 1 at the switch), then the new group alone. A jump J at a switch becomes
B + 1 steps of J / (B + 1) on top of the prediction's own motion
(docs/switching.md). :class:`~groupfit.runtime.SwitchingRule` computes it
sample by sample; :func:`bumpless_prediction` is the same over arrays, for
the comparisons that score a grouped model through the rule's groups.
"""

from __future__ import annotations

import numpy as np

from groupfit.model import grouped_prediction


def transfer_weights(groups: np.ndarray, blend_samples: int) -> np.ndarray:
    """Per sample, the new group's weight ``w`` (1 outside a transfer); ``groups`` 0-based, non-decreasing."""
    groups = np.asarray(groups)
    weights = np.ones(len(groups))
    if blend_samples <= 0:
        return weights
    for switch in np.flatnonzero(np.diff(groups) != 0) + 1:
        for k in range(blend_samples):
            i = switch + k
            if i >= len(groups) or (k and groups[i] != groups[switch]):
                break
            weights[i] = (k + 1) / (blend_samples + 1)
    return weights


def bumpless_prediction(
    intercepts: np.ndarray, slopes: np.ndarray, inputs: np.ndarray, groups: np.ndarray, *, blend_samples: int
) -> np.ndarray:
    """The grouped prediction with the rule's bumpless transfer after every switch (``groups`` 0-based)."""
    groups = np.asarray(groups)
    new = grouped_prediction(intercepts, slopes, inputs, groups)
    weights = transfer_weights(groups, blend_samples)
    blending = weights < 1.0
    if not blending.any():
        return new
    old = grouped_prediction(intercepts, slopes, inputs[blending], groups[blending] - 1)
    out = new.copy()
    out[blending] = old + weights[blending] * (new[blending] - old)
    return out
