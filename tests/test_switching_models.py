"""Models and input streams shared by the switching, replay and export tests.

Importable from the other test modules (``from test_switching_models import …``);
the tests at the bottom check the builders themselves.
"""

from __future__ import annotations

import copy
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.data import Run, load_run
from groupfit.diagnose.augment import augment_model
from groupfit.diagnose.residual import model_inputs
from groupfit.features import Feature, lowpass
from groupfit.models import GroupedRegressor
from groupfit.runtime import RuleTables
from groupfit.synthetic import simulate_lumped

ROOT = Path(__file__).resolve().parents[1]
DATASETS = ROOT / "datasets"
SYNTHETIC = DATASETS / "synthetic_cycle.csv"
FE_MODELLING = DATASETS / "paper_cycle.csv"
FE_VALIDATION = (DATASETS / "validation_timing.csv", DATASETS / "validation_speed.csv")
DIAG_AMBIENT = (DATASETS / "diag_ambient_model.csv", DATASETS / "diag_ambient_validate.csv")
DIAG_SOURCE = (DATASETS / "diag_source_model.csv", DATASETS / "diag_source_validate.csv")

EIGHT_SENSORS = {
    f"T{k + 1}": [tau, gain]
    for k, (tau, gain) in enumerate(
        [(300, 9.0), (500, 8.0), (900, 7.0), (1400, 6.0), (2200, 5.0), (3200, 4.5), (5000, 4.0), (7000, 3.5)]
    )
}


def fit_model(run: Run, p: int, n: int = 3) -> dict:
    estimator = GroupedRegressor(p=p, n=n, search="exact").fit(run.temps, run.error)
    return estimator.to_model_file(run).to_dict()


@lru_cache(maxsize=None)
def _synthetic(p: int, n: int):
    run = load_run(SYNTHETIC, temps=["T1", "T2", "T3", "T4"])
    return fit_model(run, p, n), run


def synthetic_model(p: int = 3, n: int = 3) -> tuple[dict, Run]:
    """A grouped model fitted (exact search) on the shipped synthetic run, and that run."""
    model, run = _synthetic(p, n)
    return copy.deepcopy(model), run


def lumped_frame(schedule=None, n_samples: int = 400, seed: int = 3) -> pd.DataFrame:
    config = {"n_samples": n_samples, "sensors": EIGHT_SENSORS, "seed": seed}
    if schedule is not None:
        config["schedule"] = schedule
    return simulate_lumped(config)


@lru_cache(maxsize=None)
def _eight():
    run = load_run(lumped_frame(), temps=list(EIGHT_SENSORS), name="lumped8")
    return fit_model(run, p=6), run


def eight_sensor_model() -> tuple[dict, Run]:
    """M = 8 temperatures, p = 6: the size the benchmark times."""
    model, run = _eight()
    return copy.deepcopy(model), run


def eight_sensor_validation() -> Run:
    """Another duty cycle on the same lumped machine (the model was not fitted on it)."""
    schedule = [[2000, 1.0], [1500, 0.0], [6000, 1.0], [2500, 0.0], [3000, 0.7], [1000, 0.0], [30000, 1.0]]
    return load_run(lumped_frame(schedule, seed=5), temps=list(EIGHT_SENSORS), name="lumped8-validation")


@lru_cache(maxsize=None)
def _fe():
    run = load_run(FE_MODELLING)
    return fit_model(run, p=4), run


def fe_model() -> tuple[dict, Run]:
    """Grouped model (p = 4) of the FE modelling run; skips when the data set is not there."""
    if not FE_MODELLING.is_file():
        pytest.skip(f"{FE_MODELLING.name} is not in datasets/")
    model, run = _fe()
    return copy.deepcopy(model), run


def fe_validation_runs(model: dict) -> list[Run]:
    return [load_run(path, temps=model["temps"]) for path in FE_VALIDATION if path.is_file()]


HEAT_LAW = Feature("speed_rpm", "lowpass", tau_s=1800.0, exponent=5 / 3, scale=1000.0, start="rest")
"""The unsensed part of :func:`heat_law_frame`: a lag of the bearing heat ``(n/1000)^(5/3)`` from a cold start."""
HEAT_LAW_MODELLING = [(6000, 3000), (3000, 5000), (4000, 0), (8000, 4000), (5000, 6000), (6000, 2000), (16000, 4500)]
HEAT_LAW_VALIDATION = [(4000, 4000), (5000, 1500), (3000, 0), (9000, 5500), (6000, 2500), (7000, 3500), (14000, 5000)]
"""Spindle-speed schedules (duration s, r/min), both starting at speed from a cold machine."""


def heat_law_frame(schedule, n_samples: int = 480, period_s: float = 100.0, seed: int = 0) -> pd.DataFrame:
    """A spindle run at several speeds that starts at speed on a cold machine.

    Four sensors lag the bearing heat ``q = (n/1000)^(5/3)`` (from rest) on top
    of a drifting ambient ``T_amb``; the error is a linear function of three
    sensors plus 3 µm per unit of an unsensed part, :data:`HEAT_LAW` of the
    speed. The speed is not 0 at the first sample, so a lag that starts from
    rest differs from one that starts steady.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n_samples) * period_s
    ends = np.cumsum([d for d, _ in schedule])
    levels = np.array([n for _, n in schedule] + [schedule[-1][1]], dtype=float)
    speed = levels[np.searchsorted(ends, t, side="right")]
    heat = (speed / 1000.0) ** (5.0 / 3.0)
    ambient = 20.0 + 1.5 * np.sin(2 * np.pi * t / 43200.0) + 0.3 * np.sin(2 * np.pi * t / 7000.0)
    table = {"time_s": t}
    sensors = {"T1": (300.0, 1.2), "T2": (900.0, 0.9), "T3": (5000.0, 0.7), "T4": (12000.0, 0.5)}
    for name, (tau, gain) in sensors.items():
        table[name] = ambient + gain * lowpass(heat, tau, period_s, 0.0) + 0.02 * rng.standard_normal(n_samples)
    part = HEAT_LAW.compute(speed, period_s)
    error = 0.8 * table["T1"] + 0.5 * table["T2"] + 0.3 * table["T4"] + 3.0 * part
    table["error_um"] = error + 0.02 * rng.standard_normal(n_samples)
    table["T_amb"] = ambient + 0.02 * rng.standard_normal(n_samples)
    table["speed_rpm"] = speed
    return pd.DataFrame(table)


def heat_law_runs() -> tuple[pd.DataFrame, pd.DataFrame]:
    """The modelling and the validation run of the heat-law scenario."""
    return heat_law_frame(HEAT_LAW_MODELLING, seed=1), heat_law_frame(HEAT_LAW_VALIDATION, seed=2)


AUGMENTED = {
    # label: (data sets, fixed breaks (None: p = 0), derived inputs added one after another)
    "lowpass p=0": (DIAG_AMBIENT, None, (Feature("T_amb", "lowpass", tau_s=1800.0),)),
    "all kinds p=2": (
        DIAG_AMBIENT,
        [344, 528],
        (
            Feature("T_amb", "lowpass", tau_s=1800.0),
            Feature("T_amb", "derivative"),
            Feature("speed_rpm", "delay", delay_samples=3),
            Feature("T5"),
            Feature("T1", "lowpass", tau_s=600.0),
        ),
    ),
    "on/off p=1": (
        DIAG_SOURCE,
        [300],
        (Feature("src_zscrew_on", "lowpass", tau_s=3600.0), Feature("spindle_on", "delay", delay_samples=10)),
    ),
    "heat law p=2": (
        heat_law_runs,
        [150, 330],
        (
            HEAT_LAW,  # heat-law low-pass from rest
            Feature("speed_rpm", exponent=5 / 3, scale=1000.0),  # heat law as it is
            Feature("T_amb", "delay", delay_samples=3, start="rest"),  # a delay from rest
            Feature("speed_rpm", "lowpass", tau_s=3600.0, exponent=5 / 3, scale=1000.0),  # heat law, steady start
        ),
    ),
    "on-time p=1": (
        heat_law_runs,
        [240],
        (
            Feature("speed_rpm", "ontime", exponent=5 / 3, scale=1000.0, start="rest"),  # heat law × hours on
            Feature("speed_rpm", "ontime", start="rest"),  # speed × hours on
        ),
    ),
}
"""Models with derived inputs, built as ``groupfit diagnose`` builds them (augment_model), p = 0 and p > 0.

The data sets are two CSV files or a function returning the two runs as DataFrames.
"""


@lru_cache(maxsize=None)
def _augmented(label: str):
    data, breaks, features = AUGMENTED[label]
    modelling, validation = data() if callable(data) else data
    names = (f"{label} modelling", f"{label} validation") if callable(data) else (None, None)
    run = load_run(modelling, temps=["T1", "T2", "T3", "T4"], name=names[0])
    if breaks is None:
        estimator = GroupedRegressor(p=0, n=3, search="exact").fit(run.temps, run.error)
    else:
        estimator = GroupedRegressor(n=3, fixed_breaks=breaks).fit(run.temps, run.error)
    model = estimator.to_model_file(run, "T1").to_dict()
    for feature in features:
        model = augment_model(model, run, model_inputs(model, run), feature).to_dict()
    return model, run, load_run(validation, temps=["T1", "T2", "T3", "T4"], name=names[1])


def augmented_model(label: str) -> tuple[dict, Run]:
    """A model with derived inputs (see :data:`AUGMENTED`) and its modelling run."""
    model, run, _ = _augmented(label)
    return copy.deepcopy(model), run


def augmented_validation(label: str) -> Run:
    return _augmented(label)[2]


def readings(model: dict, run: Run) -> np.ndarray:
    """The rule's readings of a run: measured inputs, then the source columns of the derived inputs."""
    names = RuleTables.from_model(model).raw_names
    return np.column_stack([run.frame[name].to_numpy(dtype=float) for name in names])


def source_faults(raw: np.ndarray, tables: RuleTables) -> np.ndarray:
    """Faults on every source of a derived input: before any good reading, held, in fault, out of range."""
    raw = np.array(raw, dtype=float)
    hold = tables.hold_samples
    sources = sorted({d.reading for d in tables.derived})
    for k, r in enumerate(sources):
        start = 25 * k
        raw[0, r] = np.nan if k == 0 else raw[0, r]  # the first source is invalid before any good reading
        raw[start + 30 : start + 30 + hold, r] = np.nan  # held: its transform is fed the last good value
        raw[start + 200 : start + 200 + hold + 4, r] = np.inf  # sensor fault, then recovery
        raw[start + 300, r] = tables.valid_max[r] + 1.0  # out of range: held
        raw[start + 301, r] = tables.valid_min[r] - 1.0
    return raw


def derived_streams(model: dict, run: Run) -> dict[str, np.ndarray]:
    """The replay streams every export is held to on a model with derived inputs."""
    tables = RuleTables.from_model(model)
    raw = readings(model, run)
    measured = tables.n_measured
    noisy_raw = raw.copy()
    noisy_raw[:, :measured] = noisy(raw[:, :measured], 0.05, seed=1)
    n = int(model["n"])
    return {
        "modelling": raw,
        "noise 0.05 C": noisy_raw,
        f"late by {n}": shifted(raw, n),
        f"early by {n}": shifted(raw, -n),
        "faults": fault_injected(raw, tables.hold_samples, tables.criterion_reading, seed=2),
        "source faults": source_faults(raw, tables),
    }


def shifted(temps: np.ndarray, shift: int) -> np.ndarray:
    """The same run recorded ``shift`` samples later (> 0: first row repeated in front) or earlier (< 0)."""
    temps = np.asarray(temps, dtype=float)
    if shift >= 0:
        return np.vstack([np.repeat(temps[:1], shift, axis=0), temps])[: len(temps)]
    return np.vstack([temps[-shift:], np.repeat(temps[-1:], -shift, axis=0)])


def noisy(temps: np.ndarray, sigma: float = 0.05, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.asarray(temps, dtype=float) + sigma * rng.standard_normal(np.shape(temps))


def fault_injected(temps: np.ndarray, hold: int, criterion: int, seed: int = 0) -> np.ndarray:
    """Sensor faults of every kind: short NaN gaps (held), long ±inf runs (fault), huge, tiny, at the start."""
    temps = np.array(temps, dtype=float)
    n, k = temps.shape
    rng = np.random.default_rng(seed)
    temps[0, (criterion + 1) % k] = np.nan  # invalid before any good reading
    temps[20 : 20 + hold, criterion] = np.nan  # held, criterion sensor
    temps[40 : 40 + hold + 3, 0] = np.inf  # past K: sensor fault, then recovery
    temps[70, k - 1] = -np.inf
    temps[90, 1 % k] = 1e300
    temps[91, 1 % k] = -1e300
    temps[110, 0] = 1e-300  # finite but far below any valid range
    temps[130 : 130 + 2 * hold + 2, criterion] = np.nan  # criterion in fault across later samples
    for row in rng.choice(np.arange(150, n), size=min(12, max(n - 150, 0)), replace=False):
        temps[row, rng.integers(k)] = rng.choice([np.nan, np.inf, -np.inf, 1e9, -273.0])
    return temps


def streams_for(model: dict, run: Run) -> dict[str, np.ndarray]:
    """The replay streams every export is held to on one model."""
    section = model["switching"]
    n = int(model["n"])
    return {
        "modelling": run.temps,
        "noise 0.05 C": noisy(run.temps, 0.05, seed=1),
        f"late by {n}": shifted(run.temps, n),
        f"early by {n}": shifted(run.temps, -n),
        "faults": fault_injected(run.temps, section["hold_samples"], section["criterion_index"], seed=2),
    }


def test_eight_sensor_model_has_the_benchmark_size():
    model, run = eight_sensor_model()
    assert len(model["temps"]) == 8 and model["p"] == 6 and len(model["coefficients"]) == 7
    assert run.n_samples == 400


def test_shift_moves_rows_by_whole_samples():
    temps = np.arange(12.0).reshape(6, 2)
    assert np.array_equal(shifted(temps, 2)[2:], temps[:4]) and np.array_equal(shifted(temps, 2)[:2], temps[[0, 0]])
    assert np.array_equal(shifted(temps, -2)[:4], temps[2:]) and np.array_equal(shifted(temps, -2)[4:], temps[[5, 5]])


def test_fault_injection_covers_every_kind():
    model, run = synthetic_model()
    temps = fault_injected(run.temps, hold=3, criterion=0)
    assert np.isnan(temps).any() and np.isposinf(temps).any() and np.isneginf(temps).any()
    assert (np.abs(temps[np.isfinite(temps)]) > 1e6).any() and (np.abs(temps) < 1e-200).any()
