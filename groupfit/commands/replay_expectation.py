"""What a replayed run shows against the figure its model file expected of a next run (``training``)."""

from __future__ import annotations

from typing import Any, Mapping

from groupfit.commands.replay_faults import mostly_unscored
from groupfit.recordings import is_modelling_file


def expectation_check(training: Mapping[str, Any] | None, data: dict[str, Any], path) -> dict[str, Any]:
    """This run's RMS without checks against what the model file expected of a next run (``training``); empty
    without a measured error or an expectation. A file the model was fitted on is no next run, nor a run mostly
    in sensor fault (``place`` says so)."""
    training = training or {}
    expected = training.get("expected_next_run_rms_um")
    rms = data["probes"]["rms_without_checks_um"] if "probes" in data else data.get("rms_um")
    if rms is None or not isinstance(expected, (int, float)) or not expected > 0:
        return {}
    low, high = training.get("expected_next_run_range_um") or (expected, expected)
    place = "below" if rms < low else "above" if rms > high else "inside"
    if is_modelling_file(training, path):  # read only when there is a figure to place
        place = "modelling run"
    elif mostly_unscored(data):
        place = "mostly unscored"
    return {
        "expected_next_run": {
            "rms_um": float(expected),
            "range_um": [float(low), float(high)],
            "actual_rms_um": float(rms),
            "actual_over_expected": float(rms / expected),
            "place": place,
        }
    }


def expectation_line(check: dict[str, Any]) -> str:
    """The report line of :func:`expectation_check`."""
    low, high = check["range_um"]
    where = "inside the range" if check["place"] == "inside" else f"{check['place']} the range"
    if check["place"] == "modelling run":
        where = "but this file is one the model was fitted on, not a next run"
    elif check["place"] == "mostly unscored":
        where = "not placed: most of the run was not scored (readings in fault, below)"
    return (
        f"expected about {check['rms_um']:.3g} µm RMS on a next run (range {low:.3g}-{high:.3g} µm, from the model "
        f"file); this run without checks: {check['actual_rms_um']:.3g} µm, {check['actual_over_expected']:.2g}× "
        f"that, {where}"
    )


__all__ = ["expectation_check", "expectation_line"]
