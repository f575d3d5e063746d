"""Parse and validate FE scenario configurations (TOML tables as dicts).

Three scenario kinds: ``kind = "headstock"`` (the default; 3-D housing, see
``configs/paper_cycle.toml`` for every key with its default) and
``kind = "rod"`` (1-D spindle rod, ``configs/rod_ar1.toml``); ``kind =
"ballscrew"`` (a feed-axis ball screw, ``configs/screw_H.toml``, parsed in
:mod:`groupfit.fe.ballscrew`). Every key is
optional; unknown keys, wrong types and impossible values raise
:class:`groupfit.errors.InputError` with the key's dotted name.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .ballscrew_config import parse_ballscrew
from .geometry import HousingGeometry, MeshResolution, points_inside
from .noise import MeasurementNoise, read_noise
from .schedule import PALMGREN_SPEED_EXPONENT, AmbientProfile, EquilibriumRule, StepSchedule
from .tables import (
    ScenarioTable,
    check_alignment,
    fail,
    non_negative,
    on_off,
    read_number_section,
    read_numbers,
    read_sensors,
    step_schedule,
)
from .unsensed import HEAT_INPUTS, UnsensedPart

RESERVED_COLUMNS = {"time_s", "T_amb", "error_um", "speed_rpm", "spindle_on", "q_W_m2"}


@dataclass(frozen=True)
class Material:
    """Isotropic material; defaults are the headstock values of docs/methods.md §1."""

    density: float = 7.8e3  # kg/m³
    heat_capacity: float = 502.4  # J/(kg·K)
    conductivity: float = 46.4  # W/(m·K)
    expansion: float = 1.06e-5  # 1/K
    poisson: float = 0.3
    young: float = 209e9  # Pa


@dataclass(frozen=True)
class ThermalBoundary:
    """Heat-transfer coefficients (W/(m²·K)).

    ``convection`` applies to the outer faces (top, sides, front, rear),
    ``bore_convection`` to the bore surface outside the bearing seats, and
    ``mount_conductance`` is the contact conductance of the mounting face to
    the bed, which is held at the ambient temperature.
    """

    convection: float = 10.0
    bore_convection: float = 10.0
    mount_conductance: float = 100.0


@dataclass(frozen=True)
class BearingHeat:
    """Bearing heat at the reference speed (W) and the speed law exponent."""

    front_W: float = 102.0
    rear_W: float = 85.4
    reference_speed_rpm: float = 2000.0
    speed_exponent: float = PALMGREN_SPEED_EXPONENT


@dataclass(frozen=True)
class HeatSource:
    """An extra heat source: ``power_W`` spread uniformly over the boundary
    facets inside ``region`` (a 3×2 box in metres) while its schedule is 1."""

    name: str
    power_W: float
    region: tuple[tuple[float, float], ...]
    schedule: StepSchedule


@dataclass(frozen=True)
class HeadstockScenario:
    geometry: HousingGeometry = field(default_factory=HousingGeometry)
    resolution: MeshResolution = field(default_factory=MeshResolution)
    material: Material = field(default_factory=Material)
    boundary: ThermalBoundary = field(default_factory=ThermalBoundary)
    bearings: BearingHeat = field(default_factory=BearingHeat)
    ambient: AmbientProfile = field(default_factory=AmbientProfile)
    spindle: StepSchedule = StepSchedule(((3000.0, 2000.0), (1000.0, 0.0), (4000.0, 2000.0), (1000.0, 0.0)))
    hold_until_equilibrium_rpm: float | None = 2000.0
    equilibrium: EquilibriumRule = field(default_factory=EquilibriumRule)
    sampling_period_s: float = 100.0
    substeps: int = 4
    max_duration_s: float = 172800.0
    error_direction: tuple[float, float, float] = (0.0, 1.0, 0.0)
    sensors: dict = field(default_factory=dict)
    candidates: str = "none"
    candidate_count: int = 0
    sources: tuple[HeatSource, ...] = ()
    unsensed_part: UnsensedPart | None = None
    noise: MeasurementNoise = field(default_factory=MeasurementNoise)
    prerun: StepSchedule | None = None
    """Warm start: ``[duration_s, speed_rpm]`` steps the spindle runs before t = 0 (not recorded)."""


@dataclass(frozen=True)
class RodScenario:
    length: float = 0.8
    radius: float = 0.1
    conductivity: float = 50.0
    density: float = 7850.0
    heat_capacity: float = 460.0
    expansion: float = 12e-6
    convection: float = 55.0
    elements: int = 40
    order: int = 2
    sampling_period_s: float = 30.0
    substeps: int = 3
    flux: StepSchedule = StepSchedule(((14400.0, 2000.0), (5400.0, 0.0), (14400.0, 3000.0), (52200.0, 0.0)))


# Sensors 2 mm under the outer surfaces, where thermocouples or PT100 probes
# would be fitted on a real housing.
DEFAULT_SENSORS = {
    "T1": (0.20, 0.448, 0.45),  # top face, above the front bearing
    "T2": (0.20, 0.448, 0.05),  # top face, above the rear bearing
    "T3": (0.398, 0.30, 0.25),  # side face at axis height, mid-length
    "T4": (0.30, 0.30, 0.498),  # front face beside the spindle nose
    "T5": (0.20, 0.20, 0.002),  # rear face below the bore
    "T6": (0.398, 0.02, 0.25),  # side face just above the mounting face
}


def parse_config(config: dict):
    """Validate a parsed TOML scenario and return its scenario object.

    Raises
    ------
    InputError
        On a missing ``kind``, an unknown key, a wrong type or an invalid value.
    """
    top = ScenarioTable(config, "")
    kind = top.get("kind", "headstock")
    if kind not in ("headstock", "rod", "ballscrew"):
        raise fail("kind", f'must be "headstock", "rod" or "ballscrew", got {kind!r}')
    top.string("description", "")
    top.string("name", "")
    if kind == "ballscrew":
        scenario = parse_ballscrew(top)
    else:
        scenario = _parse_headstock(top) if kind == "headstock" else _parse_rod(top)
    top.finish()
    return scenario


def _parse_time(top: ScenarioTable, default_period, default_substeps, default_steps, value_check, *, headstock: bool):
    time = top.sub("time")
    period = time.number("sampling_period_s", default_period, positive=True)
    substeps = time.integer("substeps", default_substeps)
    schedule = step_schedule(time, "schedule", default_steps, value_check=value_check)
    check_alignment(schedule, time.key("schedule"), period / substeps)
    extra = {}
    if headstock:
        hold = time.get("hold_until_equilibrium_rpm", 2000.0)
        if hold is False:
            hold = None
        elif isinstance(hold, bool) or not isinstance(hold, (int, float)) or hold < 0:
            raise fail(
                time.key("hold_until_equilibrium_rpm"), f"expected a non-negative speed in r/min or false, got {hold!r}"
            )
        extra["hold_until_equilibrium_rpm"] = None if hold is None else float(hold)
        extra["max_duration_s"] = time.number("max_duration_s", 172800.0, positive=True)
        extra["equilibrium"] = EquilibriumRule(
            window_s=time.number("equilibrium_window_s", 3600.0, positive=True),
            tolerance=time.number("equilibrium_tolerance", 0.005, positive=True),
        )
        if extra["max_duration_s"] < schedule.total_duration:
            raise fail(time.key("max_duration_s"), "is shorter than the schedule; raise it or shorten the schedule")
        prerun = step_schedule(time, "prerun", None, value_check=value_check)
        if prerun is not None:
            check_alignment(prerun, time.key("prerun"), period / substeps)
            extra["prerun"] = prerun
    time.finish()
    return period, substeps, schedule, extra


def _parse_headstock(top: ScenarioTable) -> HeadstockScenario:
    base = HeadstockScenario()
    g0 = base.geometry
    housing = top.sub("housing")
    geometry = HousingGeometry(
        **read_numbers(housing, g0, ("width", "height", "length", "axis_height", "bore_diameter")),
        front_seat=housing.vector("front_seat_m", g0.front_seat, 2),
        rear_seat=housing.vector("rear_seat_m", g0.rear_seat, 2),
    )
    problems = geometry.problems()
    if problems:
        raise fail("housing", problems[0])
    housing.finish()

    m0 = base.resolution
    mesh = top.sub("mesh")
    resolution = MeshResolution(
        circumferential=mesh.integer("circumferential", m0.circumferential, minimum=12),
        radial=mesh.integer("radial", m0.radial, minimum=1),
        axial_spacing=mesh.number("axial_spacing_m", m0.axial_spacing, positive=True),
        refinements=mesh.integer("refinements", m0.refinements, minimum=0),
    )
    mesh.finish()

    mat = top.sub("material")
    material = Material(**read_numbers(mat, Material()))
    if not material.poisson < 0.5:
        raise fail("material.poisson", "must be below 0.5")
    mat.finish()

    boundary = read_number_section(top, "boundary", ThermalBoundary())
    bearings = read_number_section(top, "bearings", BearingHeat())

    period, substeps, spindle, extra = _parse_time(
        top, base.sampling_period_s, base.substeps, [list(s) for s in base.spindle.steps], non_negative, headstock=True
    )
    step_s = period / substeps
    if abs(extra["equilibrium"].window_s / period - round(extra["equilibrium"].window_s / period)) > 1e-6:
        raise fail("time.equilibrium_window_s", "must be a multiple of sampling_period_s")

    ambient = _parse_ambient(top.sub("ambient"), step_s)
    noise, drift_K_per_h = _parse_noise(top.sub("noise"))
    if drift_K_per_h:
        ambient = dataclasses.replace(ambient, drift_K_per_h=drift_K_per_h)

    err = top.sub("error")
    direction = err.vector("direction", base.error_direction, 3)
    norm = math.sqrt(sum(c * c for c in direction))
    if norm == 0:
        raise fail("error.direction", "must not be the zero vector")
    err.finish()

    sensors = _parse_sensors(top.get("sensors", None), geometry)

    cand = top.sub("candidates")
    candidates = cand.string("nodes", "none", ("none", "surface", "all"))
    candidate_count = cand.integer("max_count", 0, minimum=0)
    cand.finish()

    sources = _parse_sources(top.get("sources", []), step_s, set(sensors))
    unsensed_part = _parse_unsensed_part(top.get("unsensed_part", None))

    return HeadstockScenario(
        geometry=geometry,
        resolution=resolution,
        material=material,
        boundary=boundary,
        bearings=bearings,
        ambient=ambient,
        spindle=spindle,
        sampling_period_s=period,
        substeps=substeps,
        error_direction=tuple(c / norm for c in direction),
        sensors=sensors,
        candidates=candidates,
        candidate_count=candidate_count,
        sources=tuple(sources),
        unsensed_part=unsensed_part,
        noise=noise,
        **extra,
    )


def _parse_noise(table: ScenarioTable) -> tuple[MeasurementNoise, float]:
    """The instruments' noise and ``ambient_drift_K_per_h``: physics, not a measurement, kept in ``[noise]``
    where the scenarios have always had it (:class:`AmbientProfile`)."""
    noise = read_noise(table)
    drift_K_per_h = table.number("ambient_drift_K_per_h", 0.0)
    table.finish()
    return noise, drift_K_per_h


def _parse_ambient(amb: ScenarioTable, step_s: float) -> AmbientProfile:
    kind = amb.string("profile", "constant", ("constant", "sine", "steps"))
    profile = AmbientProfile(
        kind=kind,
        mean_C=amb.number("mean_C", 20.0),
        amplitude_C=amb.number("amplitude_C", 0.0, nonnegative=True),
        period_s=amb.number("period_s", 86400.0, positive=True),
        phase_s=amb.number("phase_s", 0.0),
        steps=step_schedule(amb, "steps", None),
        offsets=step_schedule(amb, "offsets", None),
    )
    if kind == "steps":
        if profile.steps is None:
            raise fail(amb.key("steps"), 'is required when profile = "steps"')
        check_alignment(profile.steps, amb.key("steps"), step_s)
    if profile.offsets is not None:
        check_alignment(profile.offsets, amb.key("offsets"), step_s)
    amb.finish()
    return profile


def _parse_unsensed_part(raw) -> UnsensedPart | None:
    """``[unsensed_part]``: a lumped, unsensed part lagging the machine's heat
    (see :mod:`groupfit.fe.unsensed`); absent means none."""
    if raw is None:
        return None
    part = ScenarioTable(raw, "unsensed_part")
    for key in ("tau_s", "gain_um_per_W"):
        if key not in raw:
            raise fail(part.key(key), "is required in [unsensed_part]")
    unsensed = UnsensedPart(
        tau_s=part.number("tau_s", None, positive=True),
        gain_um_per_W=part.number("gain_um_per_W", None),
        heat=part.string("heat", "bearings", HEAT_INPUTS),
    )
    part.finish()
    return unsensed


def _parse_sensors(raw, geometry: HousingGeometry) -> dict:
    def reserved(name: str) -> bool:
        return name in RESERVED_COLUMNS or name.startswith(("node_", "src_"))

    def position(key: str, point) -> tuple[float, float, float]:
        if (
            not isinstance(point, (list, tuple))
            or len(point) != 3
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in point)
        ):
            raise fail(key, f"expected [x_m, y_m, z_m], got {point!r}")
        xyz = tuple(float(v) for v in point)
        if not points_inside(geometry, np.array(xyz)[:, None])[0]:
            raise fail(
                key, f"point {xyz} is outside the housing material; move it inside the housing (not in the bore)"
            )
        return xyz

    return read_sensors(raw, DEFAULT_SENSORS, layout="[x_m, y_m, z_m]", reserved=reserved, position=position)


def _parse_sources(raw, step_s: float, sensor_names: set) -> list[HeatSource]:
    if not isinstance(raw, list):
        raise fail("sources", "must be an array of tables ([[sources]])")
    sources, names = [], set()
    for i, item in enumerate(raw):
        src = ScenarioTable(item, f"sources[{i + 1}]")
        name = src.string("name", "")
        if not name.isidentifier():
            raise fail(src.key("name"), f"must be a plain identifier, got {name!r}")
        if name in names:
            raise fail(src.key("name"), f"duplicate source name {name!r}")
        names.add(name)
        power = src.number("power_W", 0.0, nonnegative=True)
        region_raw = src.get("region_m", None)
        if (
            not isinstance(region_raw, list)
            or len(region_raw) != 3
            or any(
                not isinstance(r, list)
                or len(r) != 2
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in r)
                or r[0] > r[1]
                for r in region_raw
            )
        ):
            raise fail(src.key("region_m"), "expected [[x0, x1], [y0, y1], [z0, z1]] in metres with x0 <= x1 …")
        schedule = step_schedule(src, "schedule", [[1.0, 1.0]], value_check=on_off)
        if "schedule" in item:
            check_alignment(schedule, src.key("schedule"), step_s)
        schedule = StepSchedule(schedule.steps, src.boolean("repeat", False))
        src.finish()
        sources.append(
            HeatSource(
                name=name,
                power_W=power,
                region=tuple(tuple(float(v) for v in r) for r in region_raw),
                schedule=schedule,
            )
        )
    return sources


def _parse_rod(top: ScenarioTable) -> RodScenario:
    d = RodScenario()
    rod = top.sub("rod")
    fields = ("length", "radius", "conductivity", "density", "heat_capacity", "expansion", "convection")
    values = read_numbers(rod, d, fields)
    rod.finish()
    mesh = top.sub("mesh")
    values["elements"] = mesh.integer("elements", d.elements)
    values["order"] = mesh.integer("order", d.order)
    if values["order"] > 2:
        raise fail("mesh.order", "must be 1 or 2")
    mesh.finish()
    period, substeps, flux, _ = _parse_time(
        top, d.sampling_period_s, d.substeps, [list(s) for s in d.flux.steps], None, headstock=False
    )
    return RodScenario(sampling_period_s=period, substeps=substeps, flux=flux, **values)
