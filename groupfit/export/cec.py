"""SINUMERIK 840D sag / cross-error compensation table (CEC) of a position model (``export --target cec``).

The controller's interpolatory compensation (function manual "Extended
functions", K3) adds to an output axis a value interpolated linearly in an
equidistant table over the position of an input axis. The table is a part
program file ``%_N_NC_CEC_INI`` of system variables, index ``t`` the table::

    $AN_CEC[t,N]          compensation value at interpolation point N (mm)
    $AN_CEC_INPUT_AXIS[t] the base axis whose position is the table's input
    $AN_CEC_OUTPUT_AXIS[t] the axis the value is added to
    $AN_CEC_STEP[t]       distance between interpolation points (mm)
    $AN_CEC_MIN[t], $AN_CEC_MAX[t]  first and last point (mm)

with ``(MAX − MIN)/STEP + 1`` points, at most MD18342 ``$MN_MM_CEC_MAX_POINTS[t]``,
and ``M17`` closing the file.

A position model's error ``E(P, T)`` depends on the thermal state, a table
does not: the table is ``E`` at one state the user names (the model's inputs,
``--state T1=3.2,T2=1.1``), as the compensation ``−E`` in mm. The step is the
largest decimal step (1, 2, 2.5 or 5 times a power of ten, at least 1 µm)
whose linear interpolation stays within the tolerance of the model over the
travel (``--step`` sets it); the table starts at the travel's low end and
runs to the first point at or past its high end (beyond the travel the model
is held at its end, as the run-time rule clamps the position). The
interpolation error reached, the values' rounding to 1 nm included, is
written in the file's comments.
"""

from __future__ import annotations

import math
import re
from typing import Mapping

import numpy as np

from groupfit.errors import InputError
from groupfit.heldout.span import SPAN_KEY, beyond_span
from groupfit.model import ModelFile

DEFAULT_MAX_POINTS = 2000
"""Largest number of interpolation points of one table (MD18342 as configured; 840D sl allows 2000)."""
MAX_TABLE_INDEX = 61
"""Largest table index t (840D sl: 2 × the largest number of axes − 1)."""
VALUE_DECIMALS = 6
"""Decimals of the values in mm (1 nm)."""
STEP_MANTISSAS = (5.0, 2.5, 2.0, 1.0)
SMALLEST_STEP_MM = 0.001
AXIS_NAME = re.compile(r"^[A-Z][A-Z0-9_]{0,15}$")
SAMPLES_PER_INTERVAL = 64
STATE_LIMIT = 1.0e6
"""The largest magnitude of a thermal state's input: a temperature or rise (°C, K) or a derived input in its own
unit (a speed's low-pass in r/min)."""
STATE_MARGIN = 0.25
"""How far beyond the modelling run's span of an input (as a share of the span's width) a table's state may lie."""


def decimal_text(value: float, decimals: int = VALUE_DECIMALS) -> str:
    """``value`` with at most ``decimals`` decimals, trailing zeros dropped (``-400``, ``6.73``, ``0.001234``)."""
    text = f"{value:.{decimals}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def parse_state(text: str | None, names) -> np.ndarray:
    """The model's inputs of ``--state NAME=VALUE,...``: every input named once, numbers finite."""
    names = list(names)
    if not text:
        raise InputError(
            f"export --target cec: the table is the error at one thermal state; give it with --state "
            f"{','.join(f'{n}=VALUE' for n in names)} (the model's inputs)"
        )
    values: dict[str, float] = {}
    for part in text.split(","):
        name, _, number = part.partition("=")
        name = name.strip()
        if name not in names:
            raise InputError(f"--state {part.strip()!r}: '{name}' is not a model input ({', '.join(names)})")
        if name in values:
            raise InputError(f"--state: names '{name}' twice; give each model input once")
        try:
            values[name] = float(number)
        except ValueError:
            raise InputError(f"--state {part.strip()!r}: '{number.strip()}' is not a number") from None
        if not abs(values[name]) <= STATE_LIMIT:
            raise InputError(
                f"--state {part.strip()!r}: a thermal state's inputs lie within ±{STATE_LIMIT:g} (temperatures, "
                "rises, a speed's low-pass)"
            )
    missing = [n for n in names if n not in values]
    if missing:
        raise InputError(f"--state: no value for the model input(s) {', '.join(missing)}")
    return np.array([values[n] for n in names])


def candidate_steps(travel_mm: float) -> list[float]:
    """Decimal steps from the travel down to 1 µm, largest first."""
    steps = []
    power = 10.0 ** math.ceil(math.log10(travel_mm))
    while power >= SMALLEST_STEP_MM / 10:
        steps.extend(round(m * power, 6) for m in STEP_MANTISSAS if SMALLEST_STEP_MM <= m * power <= travel_mm)
        power /= 10.0
    return sorted(set(steps), reverse=True)


def point_count(travel_mm: float, step_mm: float) -> int:
    """The points of a table over ``travel_mm`` at ``step_mm`` (the last one at or past the travel's end)."""
    return int(math.ceil(travel_mm / step_mm - 1e-9)) + 1


class CecTable:
    """The table of one model at one thermal state: nodes, values (mm) and the interpolation error (µm)."""

    def __init__(self, model: ModelFile, state: np.ndarray, step_mm: float):
        self.model, self.state, self.step_mm = model, np.asarray(state, dtype=float), float(step_mm)
        low, high = model.position.travel_mm
        self.points = point_count(high - low, self.step_mm)
        self.min_mm = round(float(low), VALUE_DECIMALS)
        self.max_mm = round(self.min_mm + (self.points - 1) * self.step_mm, VALUE_DECIMALS)
        self.nodes_mm = self.min_mm + self.step_mm * np.arange(self.points)
        self.values_mm = np.round(-self.error_um(self.nodes_mm) / 1000.0, VALUE_DECIMALS)

    def error_um(self, positions) -> np.ndarray:
        """The model's error E(P) at the state (µm), the position clamped to the travel."""
        positions = np.asarray(positions, dtype=float)
        inputs = np.repeat(self.state[None, :], len(positions), axis=0)
        return self.model.predict_position(inputs, positions, np.zeros(len(positions), dtype=int))

    def interpolated_um(self, positions) -> np.ndarray:
        """What the controller applies at ``positions``, as an error (µm): ``−1000·`` the interpolated value."""
        return -1000.0 * np.interp(np.asarray(positions, dtype=float), self.nodes_mm, self.values_mm)

    def interpolation_error_um(self) -> float:
        """Largest |table − model| over the travel (µm), on 64 points per interval."""
        low, high = self.model.position.travel_mm
        grid = np.linspace(low, high, min(SAMPLES_PER_INTERVAL * (self.points - 1) + 1, 400_001))
        grid = np.union1d(grid, self.nodes_mm[self.nodes_mm <= high])
        return float(np.max(np.abs(self.interpolated_um(grid) - self.error_um(grid))))


def cec_table(
    model: ModelFile,
    state: np.ndarray,
    *,
    step_mm: float | None = None,
    tolerance_um: float = 0.5,
    max_points: int = DEFAULT_MAX_POINTS,
) -> tuple[CecTable, float]:
    """The table of ``model`` at ``state`` and its interpolation error (µm); the step per the module docstring."""
    low, high = model.position.travel_mm
    travel = float(high - low)
    if step_mm is not None:
        if not (math.isfinite(step_mm) and step_mm > 0):
            raise InputError(f"--step {step_mm!r}: a distance between interpolation points > 0 mm")
        if step_mm > travel:
            raise InputError(
                f"--step {step_mm:g} mm: longer than the travel {low:g} .. {high:g} mm, so the table's last point "
                f"lies beyond it; take a step of at most {travel:g} mm"
            )
        points = point_count(travel, step_mm)  # counted before the nodes are made: 1e-6 mm is 5e8
        if points > max_points:
            raise InputError(
                f"--step {step_mm:g} mm: the travel {low:g} .. {high:g} mm needs {points} points, the "
                f"controller takes at most {max_points} per table (MD18342 $MN_MM_CEC_MAX_POINTS); take a "
                f"step of at least {travel / (max_points - 1):.6g} mm"
            )
        table = CecTable(model, state, step_mm)
        return table, table.interpolation_error_um()
    for step in candidate_steps(travel):
        if point_count(travel, step) > max_points:
            break
        table = CecTable(model, state, step)
        error = table.interpolation_error_um()
        if error <= tolerance_um:
            return table, error
    raise InputError(
        f"export --target cec: no table of at most {max_points} points (MD18342 $MN_MM_CEC_MAX_POINTS) over "
        f"the travel {low:g} .. {high:g} mm interpolates the model within {tolerance_um:g} um; raise "
        "--tolerance-um or --max-points"
    )


def render_cec(
    model: ModelFile,
    *,
    state: str | None = None,
    table_index: int = 0,
    input_axis: str = "AX1",
    output_axis: str | None = None,
    step_mm: float | None = None,
    tolerance_um: float = 0.5,
    max_points: int = DEFAULT_MAX_POINTS,
) -> dict[str, str]:
    """The export target ``cec``: ``{"NC_CEC.INI": text}`` (module docstring)."""
    if model.position is None:
        raise InputError("export --target cec: the model has no position terms (fit it with --position)")
    if model.breaks:
        raise InputError(
            f"export --target cec: the model has {len(model.breaks)} break(s); a table is one curve over the "
            "position: export a model without breaks (--p 0), or the run-time rule (c, st, json)"
        )
    if not 0 <= table_index <= MAX_TABLE_INDEX:
        raise InputError(f"--table {table_index}: a table index 0 … {MAX_TABLE_INDEX}")
    if not 2 <= max_points:
        raise InputError(f"--max-points {max_points}: a table has at least 2 points")
    if not (math.isfinite(tolerance_um) and tolerance_um > 0):
        raise InputError(f"--tolerance-um {tolerance_um!r}: a positive interpolation error in um")
    output_axis = output_axis or input_axis
    for option, name in (("--base-axis", input_axis), ("--comp-axis", output_axis)):
        if not AXIS_NAME.match(name):
            raise InputError(f"{option} {name!r}: a machine or channel axis name such as AX1, X1 or Z")
    inputs = parse_state(state, model.temps)
    refuse_unmodelled_state(model, inputs)
    table, error = cec_table(model, inputs, step_mm=step_mm, tolerance_um=tolerance_um, max_points=max_points)
    refuse_beyond_clamp(model, table, _state_text(model.temps, inputs))
    return {
        "NC_CEC.INI": cec_text(
            table, error, _state_text(model.temps, inputs), t=table_index, axes=(input_axis, output_axis)
        )
    }


def refuse_unmodelled_state(model: ModelFile, inputs: np.ndarray) -> None:
    """Refuse a state with an input beyond the modelling run's span (``training.input_span``) by more than
    :data:`STATE_MARGIN` of its width: the model extrapolates there, and a table for the NC holds no fault
    flag or clamp of its own to catch it."""
    span = (model.training or {}).get(SPAN_KEY) or {}
    beyond = beyond_span(span, model.temps, np.asarray(inputs, dtype=float)[None, :], STATE_MARGIN)
    if beyond:
        name, (low, high), (value, _) = beyond[0]["input"], beyond[0]["span"], beyond[0]["run"]
        margin = STATE_MARGIN * max(high - low, 1e-9)
        raise InputError(
            f"--state {name}={value:g}: the modelling run's {name} spans {low:.4g} .. {high:.4g}, and the "
            f"model is not extrapolated beyond it by more than {100 * STATE_MARGIN:g} % of that span into a "
            f"table for the NC: give a state within {low - margin:.4g} .. {high + margin:.4g}, or refit on a "
            "run that reaches it"
        )


def refuse_beyond_clamp(model: ModelFile, table: CecTable, state: str) -> None:
    """Refuse a table holding a compensation the model's run-time rule would never output (beyond its clamp
    ``switching.comp_min_um`` … ``comp_max_um``)."""
    low, high = model.switching.comp_min_um, model.switching.comp_max_um
    if low is None or high is None:
        return
    values_um = 1000.0 * table.values_mm
    beyond = np.flatnonzero((values_um < low - 1e-6) | (values_um > high + 1e-6))
    if beyond.size:
        worst = int(beyond[np.argmax(np.abs(values_um[beyond]))])
        raise InputError(
            f"--state {state}: the table's compensation reaches {values_um[worst]:.4g} um at "
            f"{table.nodes_mm[worst]:g} mm, beyond the model's clamp {low:g} .. {high:g} um, which its run-time "
            "rule never exceeds; give a state within the modelling run (or, if the machine allows a larger "
            "correction, widen switching.comp_min_um / comp_max_um in the model file)"
        )


def _state_text(names, values) -> str:
    return ", ".join(f"{n} = {v:g}" for n, v in zip(names, values))


def cec_text(table: CecTable, error_um: float, state: str, *, t: int, axes: tuple[str, str]) -> str:
    """The ``%_N_NC_CEC_INI`` file of one table."""
    low, high = table.model.position.travel_mm
    lines = [
        "%_N_NC_CEC_INI",
        "CHANDATA(1)",
        f"; groupfit position model ({table.model.position.column}, order {table.model.position.order}): "
        f"compensation = -E(P) in mm at the thermal state {state}",
        f"; table {t}: {table.points} points, step {decimal_text(table.step_mm)} mm over the travel "
        f"{low:g} .. {high:g} mm; interpolation error {error_um:.4g} um",
        f"; needs MD18342 $MN_MM_CEC_MAX_POINTS[{t}] >= {table.points}, MD32710 $MA_CEC_ENABLE = 1 on "
        f"{axes[1]}, SD41300 $SN_CEC_TABLE_ENABLE[{t}] = 1",
    ]
    lines += [f"$AN_CEC[{t},{n}]={decimal_text(v)}" for n, v in enumerate(table.values_mm)]
    lines += [
        f"$AN_CEC_INPUT_AXIS[{t}]=({axes[0]})",
        f"$AN_CEC_OUTPUT_AXIS[{t}]=({axes[1]})",
        f"$AN_CEC_STEP[{t}]={decimal_text(table.step_mm)}",
        f"$AN_CEC_MIN[{t}]={decimal_text(table.min_mm)}",
        f"$AN_CEC_MAX[{t}]={decimal_text(table.max_mm)}",
        f"$AN_CEC_DIRECTION[{t}]=0",
        f"$AN_CEC_MULT_BY_TABLE[{t}]=0",
        f"$AN_CEC_IS_MODULO[{t}]=0",
        "M17",
    ]
    return "\n".join(lines) + "\n"


def cec_options(options: Mapping) -> dict:
    """The options of :func:`render_cec` among :func:`groupfit.export.render`'s keyword options."""
    keys = ("state", "table_index", "input_axis", "output_axis", "step_mm", "tolerance_um", "max_points")
    return {key: options[key] for key in keys if options.get(key) is not None}


__all__ = ["CecTable", "DEFAULT_MAX_POINTS", "cec_table", "cec_text", "parse_state", "render_cec"]
