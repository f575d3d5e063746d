"""The bumpless transfer in the JSON runtime table: format ``groupfit-runtime/6`` and its step in words.

A table whose model switches hard (``blend_samples`` 0: a model file written
before the transfer) keeps its format; otherwise the table gains
``blend_samples`` and the step below, and says ``/6`` so that a runtime
written for an earlier format refuses it instead of switching hard.
"""

from __future__ import annotations

from groupfit.runtime import RuleTables

RUNTIME_FORMAT_6 = "groupfit-runtime/6"
"""A bumpless transfer after a switch (a superset of /5)."""

TRANSFER_STEP = (
    "bumpless transfer: blend starts at 0; when the group advanced at this sample, blend = blend_samples. "
    "While blend > 0 and not faulted, the prediction (position terms included) is computed for group - 1 "
    "(old) and for group (new) and prediction = old + w * (new - old), with w = (blend_samples + 1 - blend) / "
    "(blend_samples + 1) (whole numbers converted exactly, one division); k0 and slope of a position model move "
    "alike, from the old group's. After the prediction (faulted or "
    "not): if blend > 0 then blend -= 1"
)


def with_transfer(table: dict, tables: RuleTables) -> dict:
    """The runtime table with the transfer's length and step (unchanged for a hard switch)."""
    if tables.blend_samples <= 0 or tables.n_windows == 0:
        return table
    steps = list(table["steps"])
    at = next(i for i, step in enumerate(steps) if step.startswith("target = min(max("))
    steps.insert(at, TRANSFER_STEP)
    return {**table, "format": RUNTIME_FORMAT_6, "blend_samples": tables.blend_samples, "steps": steps}
