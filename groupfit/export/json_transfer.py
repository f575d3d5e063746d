"""The bumpless transfer in the JSON runtime table: format ``groupfit-runtime/7`` and its step in words.

A table whose model switches hard (``blend_samples`` 0: a model file written
before the transfer) keeps its format; otherwise the table gains
``blend_samples`` and the step below, and says ``/7`` so that a runtime
written for an earlier format refuses it instead of switching hard (``/6``
blended the old group's prediction with the new one's; ``/7`` closes the gap
from the last output, so a runtime for ``/6`` would compute otherwise).
"""

from __future__ import annotations

from groupfit.runtime import RuleTables

RUNTIME_FORMAT_7 = "groupfit-runtime/7"
"""A bumpless transfer after a switch that closes the gap from the last output (a superset of /5)."""

TRANSFER_STEP = (
    "bumpless transfer: blend starts at 0, has_previous false, previous and gap 0; when the group advanced at "
    "this sample, blend = blend_samples and gap = 0. When not faulted, after the serving group's prediction (position "
    "terms included): if the group advanced at this sample and has_previous, gap = previous - prediction; while "
    "blend > 0, share = w * gap with w = blend / (blend_samples + 1) (whole numbers converted exactly, one "
    "division) and prediction = prediction + share (k0 of a position model + share too); then previous = "
    "prediction and has_previous = true. After the prediction: if faulted, has_previous = false; if blend > 0 "
    "then blend -= 1"
)


def with_transfer(table: dict, tables: RuleTables) -> dict:
    """The runtime table with the transfer's length and step (unchanged for a hard switch)."""
    if tables.blend_samples <= 0 or tables.n_windows == 0:
        return table
    steps = list(table["steps"])
    at = next(i for i, step in enumerate(steps) if step.startswith("target = min(max("))
    steps.insert(at, TRANSFER_STEP)
    return {**table, "format": RUNTIME_FORMAT_7, "blend_samples": tables.blend_samples, "steps": steps}
