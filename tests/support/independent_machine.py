"""An independent lumped RC thermal model of a machine tool, and the diagnosis scenarios built on it.

The simulator uses numpy and scipy only; it shares no code with groupfit's own
simulators (``groupfit.synthetic``, ``groupfit.fe``), so a diagnosis that works
here does not merely recover the assumptions it was written with.

Thermal network (temperatures in °C, heat in W, capacities in J/K, conductances in W/K):

====  ==========================================  ==========  ===========  ==================================
node  part                                        capacity    to ambient   coupling / heat input
====  ==========================================  ==========  ===========  ==================================
B     spindle bearing (sensed, ``T1``)            20e3        2            to H: 10; spindle heat
H     headstock (sensed, ``T2``)                  200e3       8            to C: 5
C     column (sensed, ``T3``)                     800e3       15           to D: 10
D     bed (sensed, ``T4``)                        2e6         30
U     thin part, not sensed (τ ≈ 23 min)          30e3        20           to C: 2; follows the air
S     part heated by the spindle, not sensed      τ_S · 18    18           spindle heat
P     hydraulic / pump part, not sensed           τ_P · 63    60           to C: 3; pump heat when on
====  ==========================================  ==========  ===========  ==================================

The spindle heats B with ``q_bearing · (n/1000)^(5/3)`` (+ a constant when an
on/off spindle is on) and S with ``q_hidden · (n/1000)^(5/3)``; the pump heats
P with ``q_pump`` while on. The ambient is a base temperature plus a daily
sine, an air-conditioning step (10 min lag) and a door-open dip. Sensors read
the nodes with Gaussian noise, quantised to 0.01 K. The thermal error (µm) is
``Σ k_i (T_i − 20)`` over the nodes that act on the tool position, plus probe
noise; in the *heat-driven* ("pure") scenarios an unsensed node acts through
its heat-driven rise only, so exactly one effect is missing from the sensors.

Each :class:`Scenario` is a modelling run and a validation run (pandas
DataFrames built in memory, seeded, so every call gives the same numbers), the
column(s) that carry the missing effect (none when nothing is missing), the
base model's temperature inputs, and the true hidden node's temperature for
the oracle (least squares on the sensors plus that node).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.linalg import expm

NODES = ("B", "H", "C", "D", "U", "S", "P")
"""Node names, in the order of the state vector."""

SENSED_NODES = ("B", "H", "C", "D")
SENSOR_NAMES = ("T1", "T2", "T3", "T4")

CAPACITY_J_PER_K = {"B": 20e3, "H": 200e3, "C": 800e3, "D": 2e6, "U": 30e3}
TO_AMBIENT_W_PER_K = {"B": 2.0, "H": 8.0, "C": 15.0, "D": 30.0, "U": 20.0, "S": 18.0, "P": 60.0}
COUPLINGS_W_PER_K = (("B", "H", 10.0), ("H", "C", 5.0), ("C", "D", 10.0), ("U", "C", 2.0), ("P", "C", 3.0))
HEAT_EXPONENT = 5.0 / 3.0

ERROR_GAIN_UM_PER_K = {"B": 1.5, "H": 3.0, "C": -2.5, "D": 1.0}
"""Thermal-error sensitivity of the sensed nodes (µm/K)."""

SPEED_MODELLING = [(1, 0), (2, 2000), (1.5, 4000), (2, 0), (2, 6000), (1.5, 3000), (3, 0), (2, 5000), (2, 1000), (3, 0)]
SPEED_VALIDATION = [(0.5, 0), (2.5, 5000), (1, 0), (2, 3000), (2, 6000), (3, 0), (2, 2000), (3, 0)]
PUMP_MODELLING = [(1, 0), (3, 1), (2, 0), (4, 1), (3, 0), (2, 1), (5, 0)]
PUMP_VALIDATION = [(2, 1), (2, 0), (3, 1), (4, 0), (2, 1), (3, 0)]
SPINDLE_ON_MODELLING = [(1, 0), (3, 1), (2, 0), (2, 1), (1, 0), (4, 1), (7, 0)]
SPINDLE_ON_VALIDATION = [(0.5, 0), (2, 1), (3, 0), (4, 1), (6.5, 0)]
AMBIENT_MODELLING = {"phase_h": 0.0, "hvac": (8.0, 1.0), "door": (14.0, -2.0, 0.5)}
AMBIENT_VALIDATION = {"phase_h": 9.0, "hvac": (5.0, -0.8), "door": (11.0, -2.5, 0.4)}


def ambient_temperature(
    time_s,
    base_c=20.0,
    daily_amplitude_k=1.5,
    phase_h=0.0,
    hvac=None,
    door=None,
    drift_k_per_h=0.0,
):
    """Air temperature of the workshop.

    Parameters
    ----------
    time_s : ndarray
        Times (s) from the start of the run.
    base_c, daily_amplitude_k, phase_h : float
        Mean temperature, amplitude and phase (h) of the 24 h sine.
    hvac : tuple of (float, float), optional
        ``(time_h, step_k)``: the air-conditioning setpoint steps by ``step_k``
        at ``time_h``; the air follows it with a 10 min lag.
    door : tuple of (float, float, float), optional
        ``(time_h, dip_k, duration_h)``: a door opened at ``time_h`` for
        ``duration_h`` pulls the air towards ``base + dip_k`` (2 min lag) and it
        recovers with a 5 min lag after the door closes.
    drift_k_per_h : float
        A linear drift of the air.

    Returns
    -------
    ndarray
        Air temperature (°C) at ``time_s``.
    """
    hours = time_s / 3600.0
    air = base_c + daily_amplitude_k * np.sin(2 * np.pi * (hours - phase_h) / 24.0) + drift_k_per_h * hours
    if hvac is not None:
        start_h, step_k = hvac
        air = air + np.where(hours >= start_h, step_k * (1 - np.exp(-(hours - start_h) * 3600 / 600.0)), 0.0)
    if door is not None:
        start_h, dip_k, duration_h = door
        open_ = (hours >= start_h) & (hours < start_h + duration_h)
        closed_after = hours >= start_h + duration_h
        air = air + np.where(open_, dip_k * (1 - np.exp(-(hours - start_h) * 3600 / 120.0)), 0.0)
        dip_at_close = dip_k * (1 - np.exp(-duration_h * 3600 / 120.0))
        recovery = np.exp(-(hours - start_h - duration_h) * 3600 / 300.0)
        air = air + np.where(closed_after, dip_at_close * recovery, 0.0)
    return air


def piecewise_schedule(time_s, segments):
    """A value held over consecutive segments.

    Parameters
    ----------
    time_s : ndarray
        Times (s).
    segments : sequence of (float, float)
        ``(duration_h, value)`` pairs, in order; after the last segment its
        value is held.

    Returns
    -------
    ndarray
        The scheduled value at each time.
    """
    values = np.zeros_like(time_s, dtype=float)
    start_h = 0.0
    for duration_h, value in segments:
        values[(time_s >= start_h * 3600) & (time_s < (start_h + duration_h) * 3600)] = value
        start_h += duration_h
    values[time_s >= start_h * 3600] = segments[-1][1]
    return values


def state_space(spindle_part_tau_h=2.0, pump_part_tau_h=0.75):
    """Continuous-time matrices ``dx/dt = A x + B u`` of the network.

    Parameters
    ----------
    spindle_part_tau_h, pump_part_tau_h : float
        Time constants (h) of the unsensed parts S and P (their capacities
        follow from these and their conductances).

    Returns
    -------
    A : ndarray, shape (7, 7)
    B : ndarray, shape (7, 4)
        Inputs ``u = [ambient °C, bearing heat W, spindle-part heat W, pump-part heat W]``.
    """
    index = {node: i for i, node in enumerate(NODES)}
    capacity = dict(CAPACITY_J_PER_K)
    capacity["S"] = spindle_part_tau_h * 3600 * TO_AMBIENT_W_PER_K["S"]
    capacity["P"] = pump_part_tau_h * 3600 * (TO_AMBIENT_W_PER_K["P"] + 3.0)
    c = np.array([capacity[node] for node in NODES])
    to_ambient = np.array([TO_AMBIENT_W_PER_K[node] for node in NODES])
    conductance = np.zeros((len(NODES), len(NODES)))
    for first, second, g in COUPLINGS_W_PER_K:
        conductance[index[first], index[second]] = conductance[index[second], index[first]] = g
    a = (conductance - np.diag(to_ambient + conductance.sum(axis=1))) / c[:, None]
    b = np.zeros((len(NODES), 4))
    b[:, 0] = to_ambient / c
    for column, node in ((1, "B"), (2, "S"), (3, "P")):
        b[index[node], column] = 1 / c[index[node]]
    return a, b


@dataclass
class Simulation:
    """One simulated run, at the logging period."""

    time_s: np.ndarray
    nodes: np.ndarray
    """Node temperatures (°C), one column per entry of :data:`NODES`."""
    nodes_without_heat: np.ndarray
    """The same ambient history with no internal heat: ``nodes - nodes_without_heat`` is the heat-driven rise."""
    ambient: np.ndarray
    speed_rpm: np.ndarray
    spindle_on: np.ndarray
    pump_on: np.ndarray
    rng: np.random.Generator
    """The run's noise generator (sensor and probe noise are drawn from it in a fixed order)."""

    def node(self, name, heat_driven_only=False):
        """Temperature of a node (°C), or only its heat-driven rise (K)."""
        i = NODES.index(name)
        return self.nodes[:, i] - self.nodes_without_heat[:, i] if heat_driven_only else self.nodes[:, i]


def simulate(
    hours,
    period_s,
    speed=None,
    spindle_on=None,
    pump=None,
    ambient=None,
    spindle_part_tau_h=2.0,
    pump_part_tau_h=0.75,
    bearing_heat_w=5.0,
    bearing_heat_on_w=80.0,
    spindle_part_heat_w=2.0,
    pump_heat_w=150.0,
    seed=0,
    step_s=10.0,
    heat_speed=None,
):
    """Simulate the machine from a uniform start at the air temperature.

    Parameters
    ----------
    hours, period_s : float
        Length of the run and logging period.
    speed, spindle_on, pump : sequence of (float, float), optional
        Schedules (see :func:`piecewise_schedule`) of the spindle speed
        (r/min), the spindle on/off state and the pump on/off state.
    ambient : dict, optional
        Keyword arguments of :func:`ambient_temperature`.
    spindle_part_tau_h, pump_part_tau_h : float
        Time constants of the unsensed parts S and P.
    bearing_heat_w, bearing_heat_on_w, spindle_part_heat_w, pump_heat_w : float
        Heat at 1000 r/min (bearing, part S), of a running on/off spindle, of the pump.
    seed : int
        Seed of the noise generator returned with the run.
    step_s : float
        Integration step (exact discretisation, zero-order hold); the logging
        period is a whole number of steps.
    heat_speed : sequence of (float, float), optional
        Speed schedule that produces the heat when it differs from the logged
        ``speed`` (e.g. reverse rotation logged as a negative speed heats by
        its magnitude). Default: ``speed``; negative speeds heat as zero.

    Returns
    -------
    Simulation
    """
    rng = np.random.default_rng(seed)
    steps_per_sample = max(1, int(round(period_s / step_s)))
    step = period_s / steps_per_sample
    time = np.arange(0, hours * 3600 + 1e-9, step)
    air = ambient_temperature(time, **(ambient or {}))
    logged_speed = piecewise_schedule(time, speed) if speed else np.zeros_like(time)
    heating_speed = piecewise_schedule(time, heat_speed) if heat_speed else logged_speed
    running = piecewise_schedule(time, spindle_on) if spindle_on else np.zeros_like(time)
    pump_state = piecewise_schedule(time, pump) if pump else np.zeros_like(time)
    speed_heat = (np.maximum(heating_speed, 0) / 1000.0) ** HEAT_EXPONENT
    heat = np.column_stack(
        [
            bearing_heat_w * speed_heat + bearing_heat_on_w * running,
            spindle_part_heat_w * speed_heat + 0.4 * bearing_heat_on_w * running,
            pump_heat_w * pump_state,
        ]
    )
    a, b = state_space(spindle_part_tau_h, pump_part_tau_h)
    n = len(NODES)
    augmented = np.zeros((n + 4, n + 4))
    augmented[:n, :n] = a * step
    augmented[:n, n:] = b * step
    discrete = expm(augmented)
    a_step, b_step = discrete[:n, :n], discrete[:n, n:]

    def integrate(heat_factor):
        inputs = np.column_stack([air, heat * heat_factor])
        forcing = inputs @ b_step.T
        state = np.full(n, air[0])
        states = np.empty((len(time), n))
        for k in range(len(time)):
            states[k] = state
            state = a_step @ state + forcing[k]
        return states

    logged = slice(0, len(time), steps_per_sample)
    return Simulation(
        time_s=time[logged],
        nodes=integrate(1.0)[logged],
        nodes_without_heat=integrate(0.0)[logged],
        ambient=air[logged],
        speed_rpm=logged_speed[logged],
        spindle_on=running[logged],
        pump_on=pump_state[logged],
        rng=rng,
    )


def sensor_reading(true_value, rng, noise_k):
    """A sensor: the true value plus Gaussian noise, quantised to 0.01 K."""
    return np.round(true_value + rng.normal(0, noise_k, len(true_value)), 2)


def thermal_error(
    sim, gains, heat_driven_only=(), zero_at_start=False, extra_um=None, probe_noise_um=0.1, over_air=False
):
    """Thermal error (µm) at the tool, as a probe measures it.

    Parameters
    ----------
    sim : Simulation
    gains : dict of str to float
        µm/K of each node that acts on the tool position.
    heat_driven_only : sequence of str
        Nodes that act through their heat-driven rise only (not their ambient part).
    zero_at_start : bool
        Error relative to the run's first sample instead of the geometry at 20 °C.
    extra_um : ndarray, optional
        An error not caused by temperature (e.g. a fixture settling), added as is.
    probe_noise_um : float
        Gaussian probe noise; the result is rounded to 1 nm.
    over_air : bool
        Error of each node's rise over the air (probe and workpiece in the air) instead of over 20 °C.
    """
    error = np.zeros(len(sim.time_s))
    for node, gain in gains.items():
        temperature = sim.node(node, heat_driven_only=node in heat_driven_only)
        if node in heat_driven_only:
            error += gain * temperature
        elif over_air:
            error += gain * (temperature - sim.ambient)
        else:
            error += gain * (temperature - (temperature[0] if zero_at_start else 20.0))
    if extra_um is not None:
        error += extra_um
    return np.round(error + sim.rng.normal(0, probe_noise_um, len(error)), 3)


def logged_run(
    sim,
    gains,
    ambient_name="T_amb",
    speed_name="spindle_rpm",
    pump_name=None,
    spindle_on_name=None,
    surface_sensors=None,
    sensor_noise_k=0.03,
    heat_driven_only=(),
    extra_um=None,
    zero_at_start=False,
    over_air=False,
):
    """The log of a run as a DataFrame: time, sensors, ambient, operating columns, error.

    Parameters
    ----------
    sim : Simulation
    gains : dict of str to float
        See :func:`thermal_error`.
    ambient_name, speed_name, pump_name, spindle_on_name : str or None
        Names of the logged columns; None leaves the column out.
    surface_sensors : sequence of (str, dict), optional
        Sensors that read a weighted mix of nodes and the air (``"air"``);
        default one sensor per sensed node (``T1`` … ``T4``).
    sensor_noise_k : float
        Noise of the machine sensors (the ambient sensor has 0.05 K).
    heat_driven_only, extra_um, zero_at_start, over_air
        See :func:`thermal_error`.
    """
    rng = sim.rng
    columns = {"time_s": sim.time_s}
    if surface_sensors is None:
        for name, node in zip(SENSOR_NAMES, SENSED_NODES):
            columns[name] = sensor_reading(sim.node(node), rng, sensor_noise_k)
    else:
        for name, weights in surface_sensors:
            mix = sum(w * (sim.ambient if node == "air" else sim.node(node)) for node, w in weights.items())
            columns[name] = sensor_reading(mix, rng, sensor_noise_k)
    if ambient_name:
        columns[ambient_name] = sensor_reading(sim.ambient, rng, 0.05)
    if speed_name:
        columns[speed_name] = sim.speed_rpm
    if pump_name:
        columns[pump_name] = sim.pump_on.astype(int)
    if spindle_on_name:
        columns[spindle_on_name] = sim.spindle_on.astype(int)
    columns["error_um"] = thermal_error(
        sim, gains, heat_driven_only=heat_driven_only, zero_at_start=zero_at_start, extra_um=extra_um, over_air=over_air
    )
    return pd.DataFrame(columns)


@dataclass
class Scenario:
    """A modelling run and a validation run with one known missing effect (or none).

    ``missing`` lists the columns that carry what the sensors miss: one column
    for a single effect, two for the physical variants whose unsensed part
    also follows the air (its heat-driven part through the operating column,
    its ambient part through the ambient column), empty when nothing is missing.
    """

    name: str
    truth: str
    missing: tuple[str, ...]
    temps: list[str]
    modelling: pd.DataFrame
    validation: pd.DataFrame
    hidden_modelling: np.ndarray | None = None
    """The true hidden input (noise-free) on the modelling run, for the oracle; None when nothing is missing."""
    hidden_validation: np.ndarray | None = None
    notes: str = ""
    over_air: str | None = None
    """The ambient column when the error follows the parts' rises over the air (the oracle then reads rises)."""


@dataclass
class ScenarioSpec:
    """How to build a :class:`Scenario` (building simulates, so it is deferred)."""

    name: str
    truth: str
    missing: tuple[str, ...]
    build: Callable[[], tuple[pd.DataFrame, pd.DataFrame, np.ndarray | None, np.ndarray | None]]
    notes: str = ""
    ambient_as_sensor: str | None = None
    over_air: str | None = None

    def make(self) -> Scenario:
        modelling, validation, hidden_modelling, hidden_validation = self.build()
        temps = [c for c in modelling.columns if is_sensor_name(c) and c != self.ambient_as_sensor]
        return Scenario(
            self.name,
            self.truth,
            self.missing,
            temps,
            modelling,
            validation,
            hidden_modelling,
            hidden_validation,
            self.notes,
            self.over_air,
        )


def is_sensor_name(column):
    """``T`` followed by digits only: a machine sensor of these runs."""
    return column.startswith("T") and column[1:].isdigit()


def _pair(modelling, validation, hidden_node=None, heat_driven_only=False, **log):
    """Build the two logs from two simulation recipes (each a dict of :func:`simulate` arguments).

    ``hidden_node`` is the unsensed node that carries the missing effect (for
    the oracle); with ``heat_driven_only`` it acts through its heat-driven rise
    only.
    """
    gains = dict(ERROR_GAIN_UM_PER_K)
    gains.update(log.pop("extra_gains", {}))
    extra = log.pop("extra_um_modelling", None)
    heat_only = (hidden_node,) if heat_driven_only and hidden_node else ()

    def build():
        runs, hidden = [], []
        for recipe, extra_um in ((modelling, extra), (validation, None)):
            sim = simulate(**recipe)
            frame = logged_run(sim, gains, heat_driven_only=heat_only, extra_um=extra_um, **log)
            node = sim.node(hidden_node, heat_driven_only=heat_driven_only) if hidden_node else None
            if node is not None and log.get("over_air") and not heat_driven_only:
                node = node - sim.ambient
            runs.append(frame)
            hidden.append(node)
        return runs[0], runs[1], hidden[0], hidden[1]

    return build


def _recipe(hours, period_s, seed, ambient, **kwargs):
    return dict(hours=hours, period_s=period_s, seed=seed, ambient=ambient, **kwargs)


def _modelling(hours=20, period_s=30, seed=0, **kwargs):
    return _recipe(hours, period_s, seed, AMBIENT_MODELLING, **kwargs)


def _validation(hours=16, period_s=30, seed=0, **kwargs):
    return _recipe(hours, period_s, seed, AMBIENT_VALIDATION, **kwargs)


def _collinear_surface_sensors():
    """14 surface sensors, each a mix of two neighbouring nodes and a little air (strongly collinear)."""
    rng = np.random.default_rng(99)
    neighbours = [("B", "H"), ("H", "B"), ("H", "C"), ("C", "H"), ("C", "D"), ("D", "C"), ("B", "H")]
    neighbours += [("H", "C"), ("C", "D"), ("D", "C"), ("H", "B"), ("C", "H"), ("D", "C"), ("B", "H")]
    sensors = []
    for i, (main, neighbour) in enumerate(neighbours):
        main_weight = rng.uniform(0.6, 0.9)
        air_weight = rng.uniform(0.0, 0.1)
        sensors.append((f"T{i + 1}", {main: main_weight, neighbour: 1 - main_weight - air_weight, "air": air_weight}))
    return sensors


def _speed_spectrum():
    """ISO 230-3 style spectrum: a new speed every 20 min, 100 r/min steps in 500 … 8000 r/min."""
    rng = np.random.default_rng(77)
    modelling = [(1 / 3, float(v)) for v in rng.integers(5, 81, 60) * 100]
    validation = [(1 / 3, float(v)) for v in rng.integers(5, 81, 48) * 100]
    return modelling, validation


REVERSE_MODELLING = [
    (1, 0),
    (2, 2000),
    (1.5, -4000),
    (2, 0),
    (2, 6000),
    (1.5, -3000),
    (3, 0),
    (2, 5000),
    (2, -1000),
    (3, 0),
]
"""Speed schedule with reverse rotation (M4) logged as negative speed."""
REVERSE_VALIDATION = [(0.5, 0), (2.5, -5000), (1, 0), (2, 3000), (2, 6000), (3, 0), (2, -2000), (3, 0)]


def _magnitude(schedule):
    return [(duration, abs(value)) for duration, value in schedule]


def scenario_specs() -> list[ScenarioSpec]:
    """Every scenario of the benchmark, in the order of the table."""
    gain_u = {"U": 3.0}
    gain_p = {"P": 2.5}
    gain_s = {"S": 4.0}
    speed_30h = SPEED_MODELLING + [(10, 0)]
    speed_24h = SPEED_VALIDATION + [(8, 0)]
    speed_12h = [(0.5, 0), (1.5, 3000), (1, 6000), (2, 0), (1.5, 4500), (1, 1500), (2, 5000), (2.5, 0)]
    speed_10h = [(1, 2000), (2, 5500), (1.5, 0), (2, 3500), (3.5, 0)]
    spectrum_modelling, spectrum_validation = _speed_spectrum()
    drift_60s = 0.15 * np.arange(0, 20 * 3600 + 1e-9, 60.0) / 3600
    sm, sv = SPEED_MODELLING, SPEED_VALIDATION
    pm, pv = PUMP_MODELLING, PUMP_VALIDATION
    specs = [
        # the air reaches the tool through an unsensed thin part (τ ≈ 23 min), under several ambient names
        ScenarioSpec(
            "amb_T_amb_30s",
            "ambient via unsensed thin part (τ ≈ 23 min)",
            ("T_amb",),
            _pair(_modelling(speed=sm, seed=1), _validation(speed=sv, seed=2), "U", extra_gains=gain_u),
        ),
        ScenarioSpec(
            "amb_ambient_C_20s",
            "ambient via unsensed thin part, 20 s sampling",
            ("ambient_C",),
            _pair(
                _modelling(period_s=20, speed=sm, seed=3),
                _validation(period_s=20, speed=sv, seed=4),
                "U",
                extra_gains=gain_u,
                ambient_name="ambient_C",
            ),
        ),
        ScenarioSpec(
            "amb_T_room_60s",
            "ambient via unsensed thin part, 60 s sampling, 30 h + 24 h",
            ("T_room",),
            _pair(
                _modelling(hours=30, period_s=60, speed=speed_30h, seed=5),
                _validation(hours=24, period_s=60, speed=speed_24h, seed=6),
                "U",
                extra_gains=gain_u,
                ambient_name="T_room",
            ),
        ),
        ScenarioSpec(
            "amb_noopcol_60s",
            "ambient via unsensed thin part; no operating column logged",
            ("T_amb",),
            _pair(
                _modelling(period_s=60, speed=sm, seed=33),
                _validation(period_s=60, speed=sv, seed=34),
                "U",
                extra_gains=gain_u,
                speed_name=None,
            ),
        ),
        # one heat source the sensors miss, acting through its heat-driven rise only
        ScenarioSpec(
            "pump_45min_30s_pure",
            "pump part lags pump_on, τ = 45 min (heat-driven part only)",
            ("pump_on",),
            _pair(
                _modelling(speed=sm, pump=pm, pump_part_tau_h=0.75, seed=7),
                _validation(speed=sv, pump=pv, pump_part_tau_h=0.75, seed=8),
                "P",
                heat_driven_only=True,
                extra_gains=gain_p,
                pump_name="pump_on",
            ),
        ),
        ScenarioSpec(
            "hydraulic_2h_60s_pure",
            "hydraulic part lags hydraulic_on, τ = 2 h, 60 s sampling (heat-driven part only)",
            ("hydraulic_on",),
            _pair(
                _modelling(period_s=60, speed=sm, pump=pm, pump_part_tau_h=2.0, seed=9),
                _validation(period_s=60, speed=sv, pump=pv, pump_part_tau_h=2.0, seed=10),
                "P",
                heat_driven_only=True,
                extra_gains=gain_p,
                pump_name="hydraulic_on",
            ),
        ),
        ScenarioSpec(
            "speed_rpm_2h_30s_pure",
            "part heated by (n/1000)^(5/3), τ = 2 h (heat-driven part only)",
            ("spindle_rpm",),
            _pair(
                _modelling(speed=sm, spindle_part_tau_h=2.0, seed=11),
                _validation(speed=sv, spindle_part_tau_h=2.0, seed=12),
                "S",
                heat_driven_only=True,
                extra_gains=gain_s,
            ),
        ),
        ScenarioSpec(
            "speed_1h_10s_pure",
            "part heated by (n/1000)^(5/3), τ = 1 h, 10 s sampling, 12 h + 10 h (heat-driven part only)",
            ("speed",),
            _pair(
                _modelling(hours=12, period_s=10, speed=speed_12h, spindle_part_tau_h=1.0, seed=13),
                _validation(hours=10, period_s=10, speed=speed_10h, spindle_part_tau_h=1.0, seed=14),
                "S",
                heat_driven_only=True,
                extra_gains=gain_s,
                speed_name="speed",
            ),
        ),
        ScenarioSpec(
            "spindle_on_1.5h_30s_pure",
            "part lags spindle_on (on/off), τ = 1.5 h (heat-driven part only)",
            ("spindle_on",),
            _pair(
                _modelling(spindle_on=SPINDLE_ON_MODELLING, spindle_part_tau_h=1.5, seed=15),
                _validation(spindle_on=SPINDLE_ON_VALIDATION, spindle_part_tau_h=1.5, seed=16),
                "S",
                heat_driven_only=True,
                extra_gains=gain_s,
                speed_name=None,
                spindle_on_name="spindle_on",
            ),
        ),
        ScenarioSpec(
            "collinear14_pump_30s_pure",
            "pump part lags pump_on, τ = 1 h; 14 collinear surface sensors (heat-driven part only)",
            ("pump_on",),
            _pair(
                _modelling(speed=sm, pump=pm, pump_part_tau_h=1.0, seed=21),
                _validation(speed=sv, pump=pv, pump_part_tau_h=1.0, seed=22),
                "P",
                heat_driven_only=True,
                extra_gains=gain_p,
                pump_name="pump_on",
                surface_sensors=_collinear_surface_sensors(),
            ),
        ),
        ScenarioSpec(
            "speed_spectrum_2h_30s_pure",
            "heat law, τ = 2 h; a new speed every 20 min, 60+ levels (heat-driven part only)",
            ("spindle_rpm",),
            _pair(
                _modelling(speed=spectrum_modelling, spindle_part_tau_h=2.0, seed=41),
                _validation(speed=spectrum_validation, spindle_part_tau_h=2.0, seed=42),
                "S",
                heat_driven_only=True,
                extra_gains=gain_s,
            ),
        ),
        ScenarioSpec(
            "speed_reverse_2h_30s_pure",
            "heat law of |n|, τ = 2 h; reverse rotation (M4) logged negative (heat-driven part only)",
            ("spindle_rpm",),
            _pair(
                _modelling(
                    speed=REVERSE_MODELLING, heat_speed=_magnitude(REVERSE_MODELLING), spindle_part_tau_h=2.0, seed=43
                ),
                _validation(
                    speed=REVERSE_VALIDATION,
                    heat_speed=_magnitude(REVERSE_VALIDATION),
                    spindle_part_tau_h=2.0,
                    seed=44,
                ),
                "S",
                heat_driven_only=True,
                extra_gains=gain_s,
            ),
        ),
        # nothing missing
        ScenarioSpec(
            "none_30s",
            "nothing missing (speed and pump logged)",
            (),
            _pair(_modelling(speed=sm, pump=pm, seed=17), _validation(speed=sv, pump=pv, seed=18), pump_name="pump_on"),
        ),
        ScenarioSpec(
            "none_noopcol_60s",
            "nothing missing; no operating column logged",
            (),
            _pair(
                _modelling(period_s=60, speed=sm, seed=31), _validation(period_s=60, speed=sv, seed=32), speed_name=None
            ),
        ),
        ScenarioSpec(
            "none_drift_60s",
            "nothing physical missing; 0.15 µm/h drift in the modelling run only",
            (),
            _pair(
                _modelling(period_s=60, speed=sm, pump=pm, seed=35),
                _validation(period_s=60, speed=sv, pump=pv, seed=36),
                pump_name="pump_on",
                extra_um_modelling=drift_60s,
            ),
            notes="the drift is no thermal effect; nothing should be added",
        ),
        # the ambient under a sensor-like name: no column is named as an ambient
        ScenarioSpec(
            "amb_named_T9_30s",
            "ambient via unsensed thin part, ambient logged under a sensor-like name, T9",
            ("T9",),
            _pair(
                _modelling(speed=sm, seed=23),
                _validation(speed=sv, seed=24),
                "U",
                extra_gains=gain_u,
                ambient_name="T9",
            ),
            ambient_as_sensor="T9",
            notes="a sensor-like name is classified as a machine sensor, not as the ambient",
        ),
        # physical variants: the unsensed part also follows the air (two effects: operating column and ambient)
        ScenarioSpec(
            "pump_45min_30s",
            "pump part, τ = 45 min, also follows the air (two effects)",
            ("pump_on", "T_amb"),
            _pair(
                _modelling(speed=sm, pump=pm, pump_part_tau_h=0.75, seed=7),
                _validation(speed=sv, pump=pv, pump_part_tau_h=0.75, seed=8),
                "P",
                extra_gains=gain_p,
                pump_name="pump_on",
            ),
        ),
        ScenarioSpec(
            "speed_rpm_2h_30s",
            "part heated by the spindle, τ = 2 h, also follows the air (two effects)",
            ("spindle_rpm", "T_amb"),
            _pair(
                _modelling(speed=sm, spindle_part_tau_h=2.0, seed=11),
                _validation(speed=sv, spindle_part_tau_h=2.0, seed=12),
                "S",
                extra_gains=gain_s,
            ),
        ),
    ]
    return specs


def scenarios(names: Sequence[str] | None = None) -> list[Scenario]:
    """Build the scenarios (all, or those named), in the order of :func:`scenario_specs`."""
    specs = scenario_specs()
    known = {spec.name for spec in specs}
    unknown = [name for name in names or () if name not in known]
    if unknown:
        raise ValueError(f"unknown scenario(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
    return [spec.make() for spec in specs if not names or spec.name in names]


def oracle_rms_um(scenario: Scenario) -> float:
    """Validation RMS (µm) of least squares on the sensors plus the true hidden input, fitted on the modelling run.

    Without a hidden input (nothing missing) it is the sensors-only fit.
    """

    def design(frame, hidden):
        air = frame[scenario.over_air].to_numpy(float) if scenario.over_air else 0.0
        columns = [frame[c].to_numpy(float) - air for c in scenario.temps]
        if hidden is not None:
            columns.append(hidden)
        return np.column_stack(columns + [np.ones(len(frame))])

    coefficients = np.linalg.lstsq(
        design(scenario.modelling, scenario.hidden_modelling), scenario.modelling["error_um"].to_numpy(), rcond=None
    )[0]
    residual = scenario.validation["error_um"].to_numpy() - design(scenario.validation, scenario.hidden_validation) @ (
        coefficients
    )
    return float(np.sqrt(np.mean(residual**2)))


RANDOM_KINDS = ("ambient", "pump", "speed", "spindle_on", "none")
"""What scenario ``r<seed>`` misses: ``RANDOM_KINDS[seed % 5]``."""


def _random_schedule(rng, hours, levels):
    """Segments of 0.5 … 3 h at levels drawn from ``levels``, until ``hours``."""
    segments, elapsed = [], 0.0
    while elapsed < hours:
        duration = float(rng.choice([0.5, 1.0, 1.5, 2.0, 2.5, 3.0]))
        segments.append((duration, float(rng.choice(levels))))
        elapsed += duration
    return segments


def _schedule_each(rng, recipes, key, levels):
    """A new :func:`_random_schedule` of ``levels`` as ``recipe[key]`` of every recipe, in order."""
    for recipe in recipes:
        recipe[key] = _random_schedule(rng, recipe["hours"], levels)


def _random_ambient(rng):
    """A workshop day: level 18 … 24 °C, daily swing 0.5 … 2.5 K at any phase, an HVAC step, a door opened."""
    return {
        "base_c": float(rng.uniform(18, 24)),
        "daily_amplitude_k": float(rng.uniform(0.5, 2.5)),
        "phase_h": float(rng.uniform(0, 24)),
        "hvac": (float(rng.uniform(2, 18)), float(rng.uniform(-1.5, 1.5))),
        "door": (float(rng.uniform(2, 18)), float(rng.uniform(-3.0, -0.5)), float(rng.uniform(0.2, 0.8))),
    }


def random_spec(seed: int, truth: str = "absolute") -> ScenarioSpec:
    """Scenario ``r<seed>``: one missing effect (or none), everything else drawn at random.

    Sampling 10 … 120 s; runs of 14 … 30 h (modelling) and 10 … 24 h
    (validation), each on its own workshop day (another level, swing, phase,
    HVAC step and door); new schedules; the hidden part's time constant
    0.4 … 4 h and its gain. ``truth="rises"``: the error follows the parts'
    rises over the air instead of their temperatures over 20 °C.
    """
    rng = np.random.default_rng(seed)
    kind = RANDOM_KINDS[seed % len(RANDOM_KINDS)]
    period = float(rng.choice([10, 20, 30, 60, 120]))
    hours = (float(rng.uniform(14, 30)), float(rng.uniform(10, 24)))
    tau_h = float(rng.uniform(0.4, 4.0))
    recipes = [
        _recipe(h, period, 2 * seed + k, _random_ambient(rng), spindle_part_tau_h=tau_h, pump_part_tau_h=tau_h)
        for k, h in enumerate(hours)
    ]
    speeds = (0, 0, 1000, 2000, 3000, 4000, 5000, 6000)
    log = {"over_air": truth == "rises"}
    hidden, missing = None, ()
    if kind != "spindle_on":
        _schedule_each(rng, recipes, "speed", speeds)
    if kind == "ambient":
        hidden, missing = "U", ("T_amb",)
        log["extra_gains"] = {"U": float(rng.uniform(1.5, 4.0))}
    elif kind == "pump":
        _schedule_each(rng, recipes, "pump", (0, 1))
        hidden, missing = "P", ("pump_on",)
        log.update(extra_gains={"P": float(rng.uniform(1.5, 4.0))}, pump_name="pump_on")
    elif kind == "speed":
        hidden, missing = "S", ("spindle_rpm",)
        log["extra_gains"] = {"S": float(rng.uniform(2.0, 5.0))}
    elif kind == "spindle_on":
        _schedule_each(rng, recipes, "spindle_on", (0, 1))
        hidden, missing = "S", ("spindle_on",)
        log.update(extra_gains={"S": float(rng.uniform(2.0, 5.0))}, speed_name=None, spindle_on_name="spindle_on")
    pure = kind in ("pump", "speed", "spindle_on")
    what = {"ambient": "ambient via an unsensed part", "none": "nothing missing"}.get(kind, f"{kind} part, heat only")
    return ScenarioSpec(
        f"r{seed}_{kind}",
        f"{what}, τ = {tau_h:.1f} h, {period:g} s sampling, error over {'the air' if truth == 'rises' else '20 °C'}",
        missing,
        _pair(*recipes, hidden, heat_driven_only=pure, **log),
        over_air="T_amb" if truth == "rises" else None,
    )


def random_scenarios(n: int, first_seed: int = 0, truth: str = "absolute") -> list[Scenario]:
    """Scenarios ``r<first_seed>`` … ``r<first_seed + n − 1>`` (see :func:`random_spec`)."""
    return [random_spec(seed, truth).make() for seed in range(first_seed, first_seed + n)]
