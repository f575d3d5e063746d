"""Ball screw scenario: the screw, its heat source, sensors and noise, read from a run configuration.

The ``kind = "ballscrew"`` table of ``groupfit simulate`` (``configs/screw_H.toml``
is the reference); :mod:`groupfit.fe.ballscrew` solves it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from groupfit.errors import InputError

from .noise import MeasurementNoise, read_noise
from .schedule import StepSchedule
from .tables import ScenarioTable, fail, on_off, read_numbers, read_sensors, step_schedule

BEARINGS = ("fixed-free", "fixed-fixed")
SOURCES = ("fixed", "nut")


@dataclass(frozen=True)
class Screw:
    """Geometry and material of the screw (steel by default)."""

    length: float = 0.30  # m
    diameter: float = 0.025  # m, the diameter of the equivalent cylinder (pitch diameter)
    lead: float = 0.005  # m per revolution
    bearings: str = "fixed-free"
    conductivity: float = 45.0  # W/(m·K)
    density: float = 7850.0  # kg/m³
    heat_capacity: float = 460.0  # J/(kg·K)
    expansion: float = 11.5e-6  # 1/K
    convection: float = 17.2  # W/(m²·K), lateral surface and free end face

    @property
    def radius(self) -> float:
        return self.diameter / 2.0

    @property
    def area(self) -> float:
        return math.pi * self.radius**2

    @property
    def diffusivity(self) -> float:
        return self.conductivity / (self.density * self.heat_capacity)

    @property
    def fin_parameter(self) -> float:
        """λ = √(2h/(k·R0)) in 1/m, the decay rate of the steady profile."""
        return math.sqrt(2.0 * self.convection / (self.conductivity * self.radius))


@dataclass(frozen=True)
class Programme:
    """The nut's travel: from ``start`` through ``moves`` of ``(target_m, speed_m_s, dwell_s)``."""

    start: float
    moves: tuple[tuple[float, float, float], ...]
    repeat: bool = True

    def _segments(self):
        """``(t0, t1, x0, x1)`` pieces of one pass (moves then dwells)."""
        t, x, pieces = 0.0, self.start, []
        for target, speed, dwell in self.moves:
            travel = abs(target - x) / speed
            if travel > 0:
                pieces.append((t, t + travel, x, target))
                t += travel
            if dwell > 0:
                pieces.append((t, t + dwell, target, target))
                t += dwell
            x = target
        return pieces, t

    def state(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nut position (m) and speed (m/s, magnitude) at the given times."""
        pieces, period = self._segments()
        times = np.asarray(times, dtype=float)
        local = np.mod(times, period) if self.repeat else np.minimum(times, period)
        position = np.full(times.shape, pieces[-1][3])
        speed = np.zeros(times.shape)
        for t0, t1, x0, x1 in pieces:
            inside = (local >= t0) & (local < t1)
            fraction = (local[inside] - t0) / (t1 - t0)
            position[inside] = x0 + fraction * (x1 - x0)
            speed[inside] = abs(x1 - x0) / (t1 - t0)
        return position, speed


@dataclass(frozen=True)
class Source:
    kind: str = "fixed"
    power_W: float = 50.0
    into_screw: float = 1.0  # fraction of power_W that enters the screw (fixed source)
    x: float = 0.0  # position of the fixed source
    schedule: StepSchedule = StepSchedule(((7200.0, 1.0),))
    nut_length: float = 0.04
    reference_speed: float = 0.05
    bearing_power_W: float = 0.0
    programme: Programme | None = None


@dataclass(frozen=True)
class BallScrewScenario:
    screw: Screw = field(default_factory=Screw)
    source: Source = field(default_factory=Source)
    elements: int = 150
    sampling_period_s: float = 5.0
    substeps: int = 5
    duration_s: float = 7200.0
    ambient_C: float = 20.0
    sensors: dict = field(default_factory=dict)
    probe: float | str = 0.16  # metres, or "nut"
    noise: MeasurementNoise = field(default_factory=MeasurementNoise)
    displacements: tuple[float, ...] = ()  # further positions whose exact displacement is written (u<mm>mm_um)


PAPER_SENSORS = {f"T{20 * i}mm": 0.02 * i for i in range(8)}
"""Seed 003's eight PT100 sensors, 0 to 14 cm from the source, 2 cm apart (names carry the position in mm)."""

RESERVED = {"time_s", "error_um", "probe_x_m", "power_W", "nut_x_m", "screw_rpm"}


# --------------------------------------------------------------------- config


def parse_ballscrew(top: ScenarioTable) -> BallScrewScenario:
    """Read the tables of a ``kind = "ballscrew"`` scenario (``configs/screw_H.toml``)."""
    try:
        return _parse_ballscrew(top)
    except InputError as exc:
        text = str(exc).replace("configs/paper_cycle.toml or configs/rod_ar1.toml", "configs/screw_H.toml")
        raise InputError(text) from None


def _parse_ballscrew(top: ScenarioTable) -> BallScrewScenario:
    d = Screw()
    s = top.sub("screw")
    screw = Screw(
        **read_numbers(s, d, ("length", "diameter", "lead")),
        bearings=s.string("bearings", d.bearings, BEARINGS),
        **read_numbers(s, d, ("conductivity", "density", "heat_capacity", "expansion", "convection")),
    )
    s.finish()

    mesh = top.sub("mesh")
    elements = mesh.integer("elements", 150, minimum=4)
    mesh.finish()

    time = top.sub("time")
    period = time.number("sampling_period_s", 5.0, positive=True)
    substeps = time.integer("substeps", 5)
    duration = time.number("duration_s", 7200.0, positive=True)
    if abs(duration / period - round(duration / period)) > 1e-9:
        raise fail("time.duration_s", f"{duration:g} s is not a multiple of sampling_period_s ({period:g} s)")
    time.finish()

    source = _parse_source(top.sub("source"), screw)

    ambient = top.sub("ambient")
    ambient_C = ambient.number("T_C", 20.0)
    ambient.finish()

    sensors = _parse_sensors(top.get("sensors", None), screw)

    probe_table = top.sub("probe")
    raw_probe = probe_table.get("x_m", 0.16)
    if raw_probe == "nut":
        if source.kind != "nut":
            raise fail("probe.x_m", '"nut" needs a moving nut ([source] kind = "nut")')
        probe: float | str = "nut"
    else:
        probe = probe_table.number("x_m", 0.16, nonnegative=True)
        if probe > screw.length:
            raise fail("probe.x_m", f"{probe:g} m is beyond the screw's end ({screw.length:g} m)")
    raw_extra = probe_table.get("displacements_m", [])
    if (
        not isinstance(raw_extra, list)
        or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v <= screw.length for v in raw_extra)
        or len(set(raw_extra)) != len(raw_extra)
    ):
        raise fail(
            "probe.displacements_m", f"expected a list of distinct positions within the screw (m), got {raw_extra!r}"
        )
    displacements = tuple(float(v) for v in raw_extra)
    probe_table.finish()

    n = top.sub("noise")
    noise = read_noise(n)
    n.finish()
    return BallScrewScenario(
        screw=screw,
        source=source,
        elements=elements,
        sampling_period_s=period,
        substeps=substeps,
        duration_s=duration,
        ambient_C=ambient_C,
        sensors=sensors,
        probe=probe,
        noise=noise,
        displacements=displacements,
    )


def _parse_source(src: ScenarioTable, screw: Screw) -> Source:
    d = Source()
    kind = src.string("kind", d.kind, SOURCES)
    power = src.number("power_W", d.power_W, nonnegative=True)
    if kind == "fixed":
        fraction = src.number("into_screw", d.into_screw, positive=True)
        if fraction > 1:
            raise fail(src.key("into_screw"), f"is the fraction of power_W entering the screw (0 to 1), got {fraction}")
        x = src.number("x_m", 0.0, nonnegative=True)
        if x > screw.length:
            raise fail(src.key("x_m"), f"{x:g} m is beyond the screw's end ({screw.length:g} m)")
        schedule = step_schedule(src, "schedule", [[1.0, 1.0]], value_check=on_off)
        source = Source(kind, power, fraction, x, schedule)
    else:
        length = src.number("nut_length_m", d.nut_length, positive=True)
        reference = src.number("reference_speed_m_s", d.reference_speed, positive=True)
        bearing = src.number("bearing_power_W", 0.0, nonnegative=True)
        start = src.number("start_m", screw.length / 2, nonnegative=True)
        raw = src.get("programme", None)
        name = src.key("programme")
        if not isinstance(raw, list) or not raw:
            raise fail(name, 'is required for kind = "nut": a list of [target_m, speed_m_s, dwell_s]')
        moves = []
        for i, move in enumerate(raw):
            if (
                not isinstance(move, list)
                or len(move) != 3
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in move)
            ):
                raise fail(name, f"move {i + 1} must be [target_m, speed_m_s, dwell_s], got {move!r}")
            target, speed, dwell = (float(v) for v in move)
            if not (0 <= target <= screw.length) or speed <= 0 or dwell < 0:
                raise fail(
                    name, f"move {i + 1}: target within the screw, speed > 0 and dwell >= 0 needed, got {move!r}"
                )
            moves.append((target, speed, dwell))
        programme = Programme(start, tuple(moves), src.boolean("repeat", True))
        if programme._segments()[1] <= 0:
            raise fail(name, "the programme takes no time; give a move or a dwell")
        source = Source(
            kind,
            power,
            nut_length=length,
            reference_speed=reference,
            bearing_power_W=bearing,
            programme=programme,
        )
    src.finish()
    return source


def _parse_sensors(raw, screw: Screw) -> dict:
    def position(key: str, x) -> float:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not 0 <= x <= screw.length:
            raise fail(key, f"expected a position in metres within the screw (0 to {screw.length:g}), got {x!r}")
        return float(x)

    layout = "x_m (distance from the source end)"
    return read_sensors(raw, PAPER_SENSORS, layout=layout, reserved=RESERVED.__contains__, position=position)
