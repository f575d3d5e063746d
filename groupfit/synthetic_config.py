"""Read and check a ``kind = "lumped"`` scenario (:mod:`groupfit.synthetic`).

Every key is optional (``configs/synthetic_cycle.toml`` shows all but ``substeps``); an
unknown key, a wrong type or a value the model cannot run raises
:class:`groupfit.errors.InputError` naming the key and the value, read with
the same helpers as the finite-element kinds (:mod:`groupfit.fe.tables`).
The data set must also be one groupfit reads back: temperatures within
:data:`groupfit.column_values.TEMP_RANGE_C`, times within
:data:`groupfit.data.MAX_TIME_S`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from groupfit.column_values import TEMP_RANGE_C
from groupfit.data import MAX_TIME_S
from groupfit.fe.config import RESERVED_COLUMNS
from groupfit.fe.tables import fail, non_negative, read_sensors, step_schedule
from groupfit.tomlconfig import Table

PAPER_SCHEDULE = ((3000.0, 1.0), (1000.0, 0.0), (4000.0, 1.0), (1000.0, 0.0), (21000.0, 1.0))
"""(duration s, relative heat) steps of the paper's cycle, the last held to 30 000 s."""

MAX_SUBSTEPS = 10_000_000
"""The most sub-steps (``n_samples × substeps``) a run computes: about 20 s and 350 MB with four sensors.

The response is integrated sub-step by sub-step, so time and memory grow with
this product; 10 000 000 is a million samples (three years at 100 s) at the
default 10 sub-steps.
"""


@dataclass(frozen=True)
class Lag:
    """A first-order thermal capacity, ``tau_s·dθ/dt = gain·q(t) − θ``.

    Attributes
    ----------
    tau_s : float
        Time constant (s), > 0: the update factor is ``exp(−dt/tau_s)``; at 0
        it divides by zero and below 0 it grows without bound.
    gain : float
        Steady temperature rise over the ambient per unit of relative heat
        (K), ≥ 0. The heat ``q`` is a spindle's heat input (never negative),
        and a passive capacity it heats settles at ``gain·q`` above the
        ambient; a negative gain would make heating cool the part below the
        ambient, which no heated part does. The update is stable for any
        finite gain, so the bound is physical, not numerical; 0 is a sensor
        the heat does not reach.
    """

    tau_s: float
    gain: float


DEFAULT_SENSORS = {
    "T1": Lag(500.0, 9.0),
    "T2": Lag(1400.0, 7.0),
    "T3": Lag(3200.0, 5.0),
    "T4": Lag(7000.0, 3.5),
}


@dataclass(frozen=True)
class LumpedScenario:
    """A checked lumped scenario; the defaults are the paper's cycle sampled every 100 s."""

    period_s: float = 100.0
    n_samples: int = 300
    substeps: int = 10
    ambient_c: float = 20.0
    noise_c: float = 0.02
    """Standard deviation of the sensors' Gaussian noise (°C)."""
    seed: int = 0
    schedule: tuple[tuple[float, float], ...] = PAPER_SCHEDULE
    """``(duration_s, relative_heat)`` steps; the last heat holds after the schedule ends."""
    sensors: dict[str, Lag] = field(default_factory=lambda: dict(DEFAULT_SENSORS))


def parse_lumped(config: dict) -> LumpedScenario:
    """Check a lumped scenario table and return the scenario.

    Parameters
    ----------
    config : dict
        The parsed TOML: ``kind`` (``"lumped"``), ``period_s`` (finite, > 0),
        ``n_samples`` (integer ≥ 2), ``substeps`` (integer ≥ 1; with
        ``n_samples`` at most :data:`MAX_SUBSTEPS`; ``n_samples × period_s``
        at most :data:`~groupfit.data.MAX_TIME_S`), ``ambient_c`` (within
        :data:`~groupfit.column_values.TEMP_RANGE_C`), ``noise_c`` (≥ 0, at
        most that range's width), ``seed`` (integer ≥ 0), ``schedule``
        (non-empty list of ``[duration_s > 0, relative_heat ≥ 0]``) and
        ``[sensors]`` (NAME = ``[tau_s, gain]``, see :class:`Lag`; not the name
        of another column).

    Returns
    -------
    LumpedScenario

    Raises
    ------
    InputError
        Naming the key and the value at fault.
    """
    top = Table(config, "")
    base = LumpedScenario()
    top.string("kind", "lumped", ("lumped",))
    period = top.number("period_s", base.period_s, positive=True)
    n_samples = top.integer("n_samples", base.n_samples, minimum=2)
    substeps = top.integer("substeps", base.substeps, minimum=1)
    _check_size(top, period, n_samples, substeps)
    scenario = LumpedScenario(
        period_s=period,
        n_samples=n_samples,
        substeps=substeps,
        ambient_c=_read_ambient(top, base.ambient_c),
        noise_c=_read_noise(top, base.noise_c),
        seed=top.integer("seed", base.seed, minimum=0),
        schedule=_read_schedule(top, base.schedule),
        sensors=read_sensors(
            top.get("sensors"),
            DEFAULT_SENSORS,
            layout="[tau_s, gain]",
            reserved=lambda name: name in RESERVED_COLUMNS,
            position=_read_lag,
        ),
    )
    top.finish()
    return scenario


def _check_size(top: Table, period: float, n_samples: int, substeps: int) -> None:
    """Refuse a run too long to compute or whose last time stamp is not a plausible time."""
    if n_samples * substeps > MAX_SUBSTEPS:
        raise top.fail(
            "n_samples",
            f"{n_samples} samples × {substeps} substeps is more than the {MAX_SUBSTEPS:,} sub-steps a lumped run "
            f"computes; use at most {MAX_SUBSTEPS // substeps:,} samples (or fewer substeps)",
        )
    if period * n_samples > MAX_TIME_S:
        raise top.fail(
            "period_s",
            f"{period!r} s × {n_samples} samples ends beyond {MAX_TIME_S:g} s, not a plausible time; "
            "give period_s in seconds or fewer samples",
        )


def _read_ambient(top: Table, default: float) -> float:
    """``ambient_c``: a temperature groupfit reads back (:data:`~groupfit.column_values.TEMP_RANGE_C`)."""
    ambient = top.number("ambient_c", default)
    low, high = TEMP_RANGE_C
    if not low <= ambient <= high:
        raise top.fail("ambient_c", f"{ambient!r} °C is outside the plausible temperatures {low:g}…{high:g} °C")
    return ambient


def _read_noise(top: Table, default: float) -> float:
    """``noise_c``: a standard deviation (≥ 0) no wider than the plausible temperatures."""
    noise = top.number("noise_c", default, nonnegative=True)
    low, high = TEMP_RANGE_C
    if noise > high - low:
        raise top.fail(
            "noise_c", f"{noise!r} °C is wider than the plausible temperatures {low:g}…{high:g} °C; lower it"
        )
    return noise


def _read_schedule(top: Table, default: tuple[tuple[float, float], ...]) -> tuple[tuple[float, float], ...]:
    """``schedule``: the steps of :func:`groupfit.fe.tables.step_schedule`, heat never negative."""
    raw = top.data.get("schedule", default)
    if not isinstance(raw, (list, tuple)) or not raw:
        raise top.fail("schedule", f"expected a non-empty list of [duration_s, relative_heat] pairs, got {raw!r}")
    return step_schedule(top, "schedule", default, value_check=non_negative).steps


def _read_lag(key: str, value) -> Lag:
    """One sensor's ``[tau_s, gain]`` (``key``: its dotted name), bounded as :class:`Lag` says."""
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 2
        or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in value)
    ):
        raise fail(key, f"expected [tau_s, gain], two finite numbers, got {value!r}")
    tau_s, gain = (float(v) for v in value)
    if tau_s <= 0:
        raise fail(key, f"the time constant tau_s must be positive (seconds), got {value[0]!r}")
    if gain < 0:
        raise fail(key, f"the gain must not be negative (K per unit of heat; heating never cools), got {value[1]!r}")
    return Lag(tau_s, gain)
