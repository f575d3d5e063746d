"""``--recalibrate METHOD|auto`` of ``groupfit fit`` and ``groupfit diagnose``: the model's recalibration section."""

from __future__ import annotations

import argparse
from typing import Sequence

import numpy as np

from groupfit.fast_response import describe, stage_of, without_stage
from groupfit.fast_response_choice import choose_stage
from groupfit.model import ModelFile
from groupfit.recalibration_tuning import METHODS


def add_recalibrate_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--recalibrate",
        choices=METHODS,
        default=None,
        help="how probe checks correct the compensation at run time (the model file's recalibration section): "
        "auto (default: the offset hold or a Kalman filter, whichever serves better on held-out stretches of the "
        "modelling runs with simulated checks every 15 min … 2 h), hold, kalman, or none; with a filter, a "
        "fast-response stage of the inputs' swings is kept where those checks show it helps (docs/recalibration.md)",
    )


def recalibrated(model: ModelFile, runs: Sequence, method: str) -> tuple[ModelFile, str]:
    """The model with its recalibration section chosen on ``runs`` ((frame, error) pairs), with or without the
    fast-response stage (:mod:`groupfit.fast_response_choice`), and the report lines."""
    model, tuning, without = choose_stage(model, runs, method)
    if tuning.section is None:
        return model.replace(recalibration=None), ""
    section = tuning.section
    minutes = "/".join(f"{t / 60:g}" for t in tuning.intervals_s)
    line = ""
    if without is not None:
        line = (
            f"\nfast    {describe(stage_of(model))}: held-out RMS with a check every {minutes} min "
            f"{_per_interval(without.rms_chosen_um)} → {_per_interval(tuning.rms_chosen_um)} µm, "
            f"without checks {without.rms_none_um:.3g} → {tuning.rms_none_um:.3g}; in sample RMS "
            f"{in_sample_rms(without_stage(model), runs):.4g} → {in_sample_rms(model, runs):.4g} µm (the model file "
            "holds the stage; the figures and coefficients above are of the model without it)"
        )
    line += f"\nrecal   {section.description}"
    if tuning.rms_hold_um:
        line += (
            f", chosen on held-out checks; RMS with a check every {minutes} min: "
            f"{_per_interval(tuning.rms_chosen_um)} µm (offset hold {_per_interval(tuning.rms_hold_um)}, "
            f"no checks {tuning.rms_none_um:.3g})"
        )
        left_out = section.chosen.get("intervals_not_scored_s")
        if left_out:
            line += f"; every {'/'.join(f'{t / 60:g}' for t in left_out)} min not scored: the run is too short"
    else:
        line += f" ({section.chosen.get('reason', 'default')})"
    return model.replace(recalibration=section), line


def in_sample_rms(model: ModelFile, runs: Sequence) -> float:
    """The model's RMS over its modelling runs ((frame, error) pairs), the samples where the error is measured."""
    residual = np.concatenate([np.asarray(error, float) - model.predict(model.inputs(frame)) for frame, error in runs])
    return float(np.sqrt(np.mean(residual[np.isfinite(residual)] ** 2)))


def _per_interval(values: Sequence[float]) -> str:
    """One figure per check interval, ``a/b/c`` to three significant digits."""
    return "/".join(f"{v:.3g}" for v in values)


__all__ = ["add_recalibrate_option", "recalibrated"]
