"""Models with a recalibration section and probe schedules, shared by the recalibration tests."""

from __future__ import annotations

import numpy as np
from test_switching_models import augmented_model, fault_injected, readings, synthetic_model

from groupfit.model import ModelFile

KALMAN = {
    "method": "kalman",
    "terms": ["offset", "drift", "gain"],
    "offset_sigma_um_per_sqrt_h": 0.7,
    "drift_sigma_um_per_h_per_sqrt_h": 0.5,
    "drift_tau_h": 2.0,
    "gain_sigma_per_sqrt_h": 0.01,
    "initial_offset_sigma_um": 2.0,
    "initial_drift_sigma_um_per_h": 0.5,
    "initial_gain_sigma": 0.3,
    "probe_sigma_um": 0.2,
    "gate_sigmas": 4.0,
    "significance_sigmas": 2.0,
    "confirm_after": 2,
    "offset_max_um": 30.0,
    "drift_max_um_per_h": 10.0,
    "gain_max": 0.5,
    "rate_um_per_sample": 0.4,
}
HOLD = {
    "method": "hold",
    "offset_sigma_um_per_sqrt_h": 3.0,
    "initial_offset_sigma_um": 5.0,
    "gate_sigmas": 5.0,
    "confirm_after": 1,
    "offset_max_um": 20.0,
    "rate_um_per_sample": 1.0,
}


def with_section(model: dict, section: dict) -> dict:
    return {**model, "recalibration": dict(section)}


def kalman_model_file(folder):
    """The synthetic model with the :data:`KALMAN` section, saved as ``folder/model.json``."""
    model, _ = synthetic_model()
    path = folder / "model.json"
    ModelFile.from_dict(with_section(model, KALMAN)).save(path)
    return path


def probe_schedule(error: np.ndarray, every: int, *, gross_at: int | None = None, seed: int = 0) -> np.ndarray:
    """The error every ``every`` samples, 0.1 µm of probe noise, +500 µm at check ``gross_at``; NaN elsewhere."""
    rng = np.random.default_rng(seed)
    probes = np.full(len(error), np.nan)
    rows = np.arange(every - 1, len(error), every)
    probes[rows] = np.asarray(error, dtype=float)[rows] + rng.normal(0.0, 0.1, len(rows))
    if gross_at is not None:
        probes[rows[gross_at]] += 500.0
    return probes


def probe_cases() -> dict[str, tuple[dict, list[np.ndarray], list[np.ndarray]]]:
    """label: (model, streams of readings, probe schedules), faults and a gross reading included."""
    cases = {}
    synthetic, run = synthetic_model()
    flat, flat_run = augmented_model("lowpass p=0")
    for label, model, model_run in (("synthetic p=3", synthetic, run), ("lowpass p=0", flat, flat_run)):
        section = model["switching"]
        temps = np.asarray(model_run.temps, dtype=float)
        if label == "lowpass p=0":
            temps = readings(model, model_run)
        faulty = fault_injected(temps, section["hold_samples"], section["criterion_index"], seed=2)
        every = max(2, len(temps) // 25)
        streams = [temps, faulty, temps]
        probes = [
            probe_schedule(model_run.error, every, gross_at=3),
            probe_schedule(model_run.error, 1, seed=1),  # a check after every sample, faults included
            probe_schedule(model_run.error + 3.0, every, gross_at=1, seed=2),
        ]
        for name, recal in (("kalman", KALMAN), ("hold", HOLD)):
            cases[f"{label} {name}"] = (with_section(model, recal), streams, probes)
    quiet = with_section(synthetic, QUIET)
    cases["synthetic p=3 switch gaps"] = (quiet, [np.asarray(run.temps, dtype=float)], [switch_gap_checks(quiet, run)])
    wide = with_section(synthetic, {**QUIET, "initial_offset_sigma_um": 5.0, "confirm_after": 2})
    stepped = probe_schedule(run.error + np.where(np.arange(run.n_samples) < run.n_samples // 2, 0.0, 12.0), 10)
    cases["synthetic p=3 a real step"] = (wide, [np.asarray(run.temps, dtype=float)], [stepped])
    cases["synthetic p=3 beyond the clamp"] = (clamped_to_half(with_section(synthetic, KALMAN), run), *wide_runs(run))
    cases["synthetic p=3 held at the clamp"] = (
        clamped_to_half(with_section(synthetic, KALMAN), run),
        [np.asarray(run.temps, dtype=float)],
        [late_checks_of_less(clamped_to_half(synthetic, run), run)],
    )
    return cases


def late_checks_of_less(model: dict, run) -> np.ndarray:
    """Checks every 40 samples from the first sample the model commands beyond its clamp on, each reading 0.8 of
    the error: the check that widens the clamp finds the model over-predicting (the offset must keep its level)."""
    from groupfit.runtime import SwitchingRule

    prediction = SwitchingRule(model).replay(run.temps).prediction_um
    first = int(np.flatnonzero(np.abs(prediction) >= model["switching"]["comp_max_um"])[0]) + 5
    probes = np.full(run.n_samples, np.nan)
    probes[first::40] = 0.8 * np.asarray(run.error, dtype=float)[first::40]
    return probes


def clamped_to_half(model: dict, run) -> dict:
    """The model with its compensation clamped to half its largest prediction over ``run``."""
    from groupfit.runtime import SwitchingRule

    plain = SwitchingRule(model).replay(run.temps)
    limit = float(np.ceil(0.5 * np.max(np.abs(plain.prediction_um))))
    return {**model, "switching": {**model["switching"], "comp_min_um": -limit, "comp_max_um": limit}}


def wide_runs(run) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The run, with checks every 5 samples, and with its error 3 µm higher checked every sample."""
    temps = np.asarray(run.temps, dtype=float)
    return [temps, temps], [probe_schedule(run.error, 5, seed=3), probe_schedule(run.error + 3.0, 1, seed=4)]


QUIET = {
    **KALMAN,
    "terms": ["offset"],
    "offset_sigma_um_per_sqrt_h": 0.01,
    "initial_offset_sigma_um": 0.05,
    "drift_sigma_um_per_h_per_sqrt_h": 0.0,
    "initial_drift_sigma_um_per_h": 0.0,
    "drift_max_um_per_h": 0.0,
    "gain_sigma_per_sqrt_h": 0.0,
    "initial_gain_sigma": 0.0,
    "gain_max": 0.0,
    "confirm_after": 3,
}
"""A filter that trusts its offset: a check off by a switch's gap passes its gate only at the switch; with a
wide initial offset a real step of 12 µm passes the gate's floor (the new run's offset prior)."""


def switch_gap_checks(model: dict, run) -> np.ndarray:
    """Checks off the rule's own prediction by each switch's gap: at the switch, and five samples before it."""
    from groupfit.runtime import SwitchingRule

    plain = SwitchingRule(model).replay(run.temps, np.full(run.n_samples, np.nan))
    blend = model["switching"].get("blend_samples", 0)
    probes = np.full(run.n_samples, np.nan)
    for i in np.flatnonzero(plain.switched):
        gap = (blend + 1) * (plain.prediction_um[i - 1] - plain.prediction_um[i])
        probes[i] = plain.prediction_um[i] + gap
        probes[i - 5] = plain.prediction_um[i - 5] + gap
    return probes
