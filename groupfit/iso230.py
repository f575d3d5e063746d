"""ISO 230-2 evaluation of bidirectional positioning runs, and a simulator of such runs.

ISO 230-2's standard test cycle moves a linear axis to m target positions
``P_i`` along its travel, n times in each direction (n = 5: runs
``j = 1…n`` forward, ↑, and back, ↓), and reads the positional deviation
``x_ij = P_ij − P_i`` (actual minus target) at each. From these (docs/iso230.md):

* mean unidirectional positional deviations ``x̄_i↑ = (1/n) Σ_j x_ij↑``,
  ``x̄_i↓`` likewise, and the mean bidirectional ``x̄_i = (x̄_i↑ + x̄_i↓)/2``;
* reversal value ``B_i = x̄_i↑ − x̄_i↓``; of the axis ``B = max |B_i|``, and
  the mean reversal value ``B̄ = (1/m) Σ_i B_i``;
* unidirectional standard uncertainty ``s_i↑ = √(Σ_j (x_ij↑ − x̄_i↑)² / (n − 1))``,
  ``s_i↓`` likewise; unidirectional repeatability ``R_i↑ = 4 s_i↑``, ``R_i↓ =
  4 s_i↓``; bidirectional ``R_i = max(2 s_i↑ + 2 s_i↓ + |B_i|, R_i↑, R_i↓)``;
  of the axis ``R↑ = max R_i↑``, ``R↓ = max R_i↓``, ``R = max R_i``;
* unidirectional systematic positional deviation ``E↑ = max x̄_i↑ − min x̄_i↑``
  (``E↓`` likewise), bidirectional ``E = max(x̄_i↑, x̄_i↓) − min(x̄_i↑, x̄_i↓)``;
* range of the mean bidirectional positional deviation ``M = max x̄_i − min x̄_i``;
* unidirectional accuracy ``A↑ = max(x̄_i↑ + 2 s_i↑) − min(x̄_i↑ − 2 s_i↑)``
  (``A↓`` likewise), bidirectional ``A = max(x̄_i↑ + 2 s_i↑, x̄_i↓ + 2 s_i↓) −
  min(x̄_i↑ − 2 s_i↑, x̄_i↓ − 2 s_i↓)``.

The runs are read as a long table: one row per approach, with the target
position (mm), the direction (``+``/``-``, ``up``/``down``, ``1``/``-1``) and
the deviation (µm). Every target must be approached equally often in each
direction (at least twice); the standard cycle's five times is reported when
it is not met, not refused. A target position must be finite and within
±:data:`TARGET_LIMIT_MM`, a deviation within ±:data:`ERROR_LIMIT_UM` (the
limit every verb puts on an error): anything else is refused with its row
(rows counted from 1, the header not a row), never evaluated.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from groupfit.column_values import ERROR_LIMIT_UM, POSITION_LIMIT_UM
from groupfit.data import numeric_column, read_table
from groupfit.default_columns import MICROMETRES_PER_UNIT, factored_length_unit, named_length_unit
from groupfit.errors import InputError
from groupfit.readtable import COMPRESSED, TABLE_SUFFIXES
from groupfit.textencoding import decode
from groupfit.textlayout import fields_of, header_delimiter, with_newlines

STANDARD_REPEATS = 5
"""Approaches per target and direction in ISO 230-2's standard test cycle."""
UP_WORDS = ("+", "up", "1", "+1", "pos", "positive", "forward", "↑")
DOWN_WORDS = ("-", "down", "-1", "neg", "negative", "backward", "↓")
TARGET_LIMIT_MM = POSITION_LIMIT_UM / 1000.0
"""Largest plausible target position (mm): 100 m, the largest position a machine's axis logs. A deviation is
plausible within ±:data:`groupfit.column_values.ERROR_LIMIT_UM` (µm), as every verb reads an error."""


@dataclass(frozen=True)
class PlausibleValues:
    """What a column of the runs holds: its unit, the largest plausible magnitude and what to do about a cell that
    is missing or beyond it."""

    unit: str
    limit: float
    when_missing: str
    when_beyond: str


TARGET_VALUES = PlausibleValues(
    "mm",
    TARGET_LIMIT_MM,
    "fill in the target position (mm) of that approach",
    "check the column's unit: target positions are read in mm unless the column's name ends in its unit (target_um)",
)
DEVIATION_VALUES = PlausibleValues(
    "µm",
    ERROR_LIMIT_UM,
    "fill in the deviation measured there (µm), or leave that target out of every run",
    "check the column's unit: deviations are read in µm, actual minus target, unless the column's name ends in "
    "its unit (deviation_nm); an actual position instead of the deviation reads far too large",
)


@dataclass(frozen=True)
class Iso230Result:
    """ISO 230-2 parameters of one axis (module docstring); arrays per target position, ascending.

    Attributes
    ----------
    targets_mm : ndarray, shape (m,)
    up, down : ndarray, shape (n, m)
        The deviations (µm) of every run, ↑ and ↓, in run order.
    """

    targets_mm: np.ndarray
    up: np.ndarray
    down: np.ndarray

    @property
    def repeats(self) -> int:
        return int(self.up.shape[0])

    @property
    def mean_up(self) -> np.ndarray:
        return self.up.mean(axis=0)

    @property
    def mean_down(self) -> np.ndarray:
        return self.down.mean(axis=0)

    @property
    def mean(self) -> np.ndarray:
        """Mean bidirectional positional deviation x̄_i."""
        return 0.5 * (self.mean_up + self.mean_down)

    @property
    def reversal(self) -> np.ndarray:
        """Reversal value B_i = x̄_i↑ − x̄_i↓."""
        return self.mean_up - self.mean_down

    @property
    def s_up(self) -> np.ndarray:
        return self.up.std(axis=0, ddof=1)

    @property
    def s_down(self) -> np.ndarray:
        return self.down.std(axis=0, ddof=1)

    @property
    def repeatability(self) -> np.ndarray:
        """Bidirectional repeatability R_i = max(2s↑ + 2s↓ + |B_i|, R_i↑, R_i↓)."""
        return np.maximum.reduce(
            [2 * self.s_up + 2 * self.s_down + np.abs(self.reversal), 4 * self.s_up, 4 * self.s_down]
        )

    def axis(self) -> dict[str, float]:
        """The axis' parameters (µm): B, B_mean, R_up, R_down, R, E_up, E_down, E, M, A_up, A_down, A."""
        up, down, s_up, s_down = self.mean_up, self.mean_down, self.s_up, self.s_down
        both = np.concatenate([up, down])
        high = np.concatenate([up + 2 * s_up, down + 2 * s_down])
        low = np.concatenate([up - 2 * s_up, down - 2 * s_down])
        values = {
            "B": np.max(np.abs(self.reversal)),
            "B_mean": np.mean(self.reversal),
            "R_up": np.max(4 * s_up),
            "R_down": np.max(4 * s_down),
            "R": np.max(self.repeatability),
            "E_up": np.ptp(up),
            "E_down": np.ptp(down),
            "E": np.ptp(both),
            "M": np.ptp(self.mean),
            "A_up": np.max(up + 2 * s_up) - np.min(up - 2 * s_up),
            "A_down": np.max(down + 2 * s_down) - np.min(down - 2 * s_down),
            "A": np.max(high) - np.min(low),
        }
        return {key: float(value) for key, value in values.items()}

    def positions(self) -> list[dict[str, float]]:
        """Per target: x̄↑, x̄↓, x̄, B_i, s↑, s↓, R_i↑, R_i↓, R_i (µm)."""
        columns = {
            "target_mm": self.targets_mm,
            "mean_up_um": self.mean_up,
            "mean_down_um": self.mean_down,
            "mean_um": self.mean,
            "B_um": self.reversal,
            "s_up_um": self.s_up,
            "s_down_um": self.s_down,
            "R_up_um": 4 * self.s_up,
            "R_down_um": 4 * self.s_down,
            "R_um": self.repeatability,
        }
        return [{key: float(values[i]) for key, values in columns.items()} for i in range(len(self.targets_mm))]

    def to_json(self) -> dict[str, Any]:
        return {
            "standard": "ISO 230-2",
            "targets": len(self.targets_mm),
            "repeats": self.repeats,
            "standard_cycle": self.repeats == STANDARD_REPEATS,
            "axis_um": self.axis(),
            "positions": self.positions(),
        }


def evaluate(up: np.ndarray, down: np.ndarray, targets_mm: Sequence[float]) -> Iso230Result:
    """The ISO 230-2 result of deviations ``up``, ``down`` (n runs × m targets, µm).

    Raises
    ------
    InputError
        Shapes that do not match, fewer than 2 runs, a target position that is not finite or beyond
        ±:data:`TARGET_LIMIT_MM`, a deviation that is not finite or beyond ±:data:`ERROR_LIMIT_UM`.
    """
    up, down = np.asarray(up, dtype=float), np.asarray(down, dtype=float)
    targets = np.asarray(targets_mm, dtype=float)
    if up.shape != down.shape or up.ndim != 2 or up.shape[1] != len(targets):
        raise InputError(f"deviations of shape {up.shape} and {down.shape} for {len(targets)} targets")
    if up.shape[0] < 2:
        raise InputError(
            f"{up.shape[0]} run(s) per direction: the repeatability needs at least 2 (ISO 230-2: 5); approach "
            "every target at least twice from each side"
        )
    _refuse_implausible(up, down, targets)
    order = np.argsort(targets, kind="stable")
    return Iso230Result(targets_mm=targets[order], up=up[:, order], down=down[:, order])


def _refuse_implausible(up: np.ndarray, down: np.ndarray, targets: np.ndarray) -> None:
    """Refuse the first target position or deviation that is not finite or beyond its plausible limit."""
    outside = ~(np.abs(targets) <= TARGET_LIMIT_MM)  # NaN too
    if outside.any():
        raise InputError(
            f"target position {targets[outside][0]:g} mm: not a position within the plausible "
            f"±{TARGET_LIMIT_MM:g} mm of an axis"
        )
    for runs, arrow in ((up, "↑"), (down, "↓")):
        outside = ~(np.abs(runs) <= ERROR_LIMIT_UM)
        if outside.any():
            run, at = np.argwhere(outside)[0]
            raise InputError(
                f"run {run + 1} {arrow} at {targets[at]:g} mm: deviation {runs[run, at]:g} µm is not within the "
                f"plausible ±{ERROR_LIMIT_UM:g} µm; check that it is in µm, actual minus target"
            )


def direction_sign(value: Any) -> int:
    """+1 for an approach in the positive direction, −1 for the negative, 0 for a word neither."""
    text = str(value).strip().lower()
    if text.endswith(".0"):
        text = text[:-2]
    if text in UP_WORDS:
        return 1
    if text in DOWN_WORDS:
        return -1
    return 0


def _cell_text(value: Any) -> str:
    """A cell as the file wrote it, quoted (``'0'``, ``'cw'``, not ``np.int64(0)``), or ``empty``.

    Parameters
    ----------
    value
        The cell as the table holds it: text, a number (a whole float written as an integer) or NaN.

    Returns
    -------
    str
    """
    if pd.isna(value) or str(value).strip() == "":
        return "empty"
    if isinstance(value, (float, np.floating)):
        number = float(value)
        return repr(str(int(number)) if number.is_integer() and abs(number) < 1e15 else repr(number))
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return repr(str(int(value)))
    return repr(str(value))


def load_runs(
    source, *, target: str = "target_mm", direction: str = "direction", deviation: str = "deviation_um"
) -> Iso230Result:
    """Read bidirectional positioning runs (a long table, module docstring) and evaluate them.

    Each target's approaches in one direction are taken in the order of the
    rows (run 1 first). Refused with the file, column and row (rows counted
    from 1, the header not a row): a missing column, a non-numeric, empty or
    implausible target (beyond ±:data:`TARGET_LIMIT_MM`) or deviation (beyond
    ±:data:`ERROR_LIMIT_UM`), a direction that is neither, a single target, a
    target approached in one direction only or unequally often, fewer than two
    runs each way.
    """
    frame, _, label = read_table(source)
    roles = {"--target": target, "--direction": direction, "--deviation": deviation}
    for (role, name), (other, same) in itertools.combinations(roles.items(), 2):
        if name == same:
            raise InputError(f"{label}: column '{name}' given as both {role} and {other}; name one column for each")
    for name in (target, direction, deviation):
        if name not in frame.columns:
            raise InputError(
                _header_read_below(source, frame, label, (target, direction, deviation))
                or f"{label}: column '{name}' not found (target position mm, direction +/-, deviation um); "
                f"the columns are: {', '.join(map(str, frame.columns))}"
            )
    table = pd.DataFrame(
        {
            "target": _plausible_column(frame, target, label, TARGET_VALUES),
            "sign": _direction_signs(frame, direction, label),
            "deviation": _plausible_column(frame, deviation, label, DEVIATION_VALUES),
        }
    )
    positions = _evenly_approached(table, label, target)
    up, down = (
        np.column_stack([table.deviation[(table.target == p) & (table.sign == sign)].to_numpy() for p in positions])
        for sign in (1, -1)
    )
    try:
        return evaluate(up, down, positions)
    except InputError as exc:
        raise InputError(f"{label}: {exc}") from None


def _header_read_below(source, frame: pd.DataFrame, label: str, names: Sequence[str]) -> str:
    """The refusal of a text table whose first line names the columns ``names`` but which was read with a row
    below it as its header; "" for any other table.

    A row with a word where a number belongs (``-,20,abc``) is mostly text in this table, whose directions are
    text: :func:`groupfit.data.read_table` takes it for the header, the rows above it for a preamble.
    """
    path = Path(source) if isinstance(source, (str, Path)) else None
    if path is None or path.suffix.lower() in COMPRESSED or TABLE_SUFFIXES.get(path.suffix.lower(), "CSV") != "CSV":
        return ""
    lines = [line for line in with_newlines(decode(path.read_bytes())).split("\n") if line.strip()]
    separator = header_delimiter(lines[0])
    cells = [[field.strip().strip('"').strip() for field in fields_of(line, separator)] for line in lines]
    read_header = [str(name) for name in frame.columns]
    if not set(names) <= set(cells[0]) or read_header not in cells[1:]:
        return ""
    row = cells.index(read_header, 1)
    return (
        f"{label}: row {row}, {lines[row].strip()!r}: text where a number belongs (a target position, a deviation) "
        "made it read as the header, the rows above it as a preamble; write the number, or leave that target out "
        "of every run"
    )


def read_in(column: str, plausible: PlausibleValues) -> tuple[str, float]:
    """The length unit ``column``'s name ends in (``deviation_nm``, ``target [µm]``) and the factor that takes
    it to ``plausible.unit``; ``plausible.unit`` and 1 when the name has none."""
    per_plausible_unit = 1000.0 if plausible.unit == "mm" else 1.0
    factored = factored_length_unit(column)  # dev [0.1 µm], P [0.1 mm]
    if factored is not None:
        return factored[0], factored[1] / per_plausible_unit
    unit = named_length_unit(column)
    if unit is None:
        return plausible.unit, 1.0
    return unit, MICROMETRES_PER_UNIT[unit] / per_plausible_unit


def _plausible_column(frame: pd.DataFrame, column: str, label: str, plausible: PlausibleValues) -> np.ndarray:
    """The column in ``plausible.unit``, refusing the first cell that is empty, not finite or beyond
    ``plausible.limit``.

    Parameters
    ----------
    frame, column, label
        The table, the column read and how messages name the table.
    plausible
        The column's unit, its limit and what to do about a bad cell; a column whose name ends in another length
        unit is read in it (:func:`read_in`).

    Returns
    -------
    ndarray
    """
    unit = read_in(column, plausible)
    values = numeric_column(frame, column, label, allow_nonfinite=True) * unit[1]
    bad = ~(np.abs(values) <= plausible.limit)  # NaN and ±inf too
    if not bad.any():
        return values
    row = int(np.flatnonzero(bad)[0])
    if np.isfinite(values[row]):
        read, canonical = ("" if unit[1] == 1.0 else f" (read in {unit[0]})"), plausible.unit
        what = f": {values[row]:g} {canonical}{read} is beyond the plausible ±{plausible.limit:g} {canonical}"
        todo = plausible.when_beyond
    else:
        what, todo = _cell_phrase(frame[column].iloc[row], "not a finite number"), plausible.when_missing
    raise InputError(f"{label}: row {row + 1}, column '{column}'{what} ({int(bad.sum())} such row(s)); {todo}")


def _cell_phrase(value: Any, fault: str) -> str:
    """What follows ``row N, column 'C'`` in a refusal: `` is empty``, or ``: 'cw' is {fault}`` (the cell as
    :func:`_cell_text` quotes it)."""
    cell = _cell_text(value)
    return " is empty" if cell == "empty" else f": {cell} is {fault}"


def _direction_signs(frame: pd.DataFrame, column: str, label: str) -> np.ndarray:
    """+1 or −1 per row, refusing the first cell that is no direction (:func:`direction_sign`)."""
    signs = np.array([direction_sign(v) for v in frame[column]])
    if np.any(signs == 0):
        row = int(np.flatnonzero(signs == 0)[0])
        raise InputError(
            f"{label}: row {row + 1}, column '{column}'{_cell_phrase(frame[column].iloc[row], 'no direction')}; "
            "write + or - (up/down, 1/-1)"
        )
    return signs


def _evenly_approached(table: pd.DataFrame, label: str, target: str) -> np.ndarray:
    """The target positions (ascending) of ``table`` (target, sign, deviation), refusing a single target and one
    approached from one side only or less often than another, with the rows of that target (counted from 1)."""
    counts = table.groupby(["target", "sign"]).size().unstack(fill_value=0)
    for sign, word in ((1, "positive"), (-1, "negative")):
        if sign not in counts.columns or (counts[sign] == 0).any():
            missing = float(counts.index[counts.get(sign, pd.Series(0, index=counts.index)) == 0][0])
            raise InputError(
                f"{label}: {_rows_of(table, missing)}, column '{target}': target {missing:.15g} mm is never "
                f"approached in the {word} direction{_near_note(counts.index, missing)}; ISO 230-2 approaches "
                "every target from both sides"
            )
    repeats, most = int(counts.to_numpy().min()), int(counts.to_numpy().max())
    if most != repeats:
        at, sign = counts.stack().idxmin()
        raise InputError(
            f"{label}: {_rows_of(table, float(at), sign)}, column '{target}': target {at:.15g} mm is approached "
            f"{repeats} time(s) in the {'+' if sign > 0 else '-'} direction, up to {most} elsewhere"
            f"{_near_note(counts.index, float(at))}: give every target the same number of runs each way"
        )
    if len(counts.index) < 2:
        raise InputError(
            f"{label}: column '{target}' holds one target position only ({counts.index[0]:g} mm); ISO 230-2 "
            "evaluates an axis at several: measure at least 2"
        )
    return counts.index.to_numpy(dtype=float)


NEAR_TARGET_MM = 1e-3
"""Two targets closer than this (1 µm) are one target mistyped, not two the axis was sent to."""


def _rows_of(table: pd.DataFrame, at: float, sign: int | None = None) -> str:
    """``row 4`` or ``rows 3, 9``: the rows (counted from 1) of target ``at`` (in direction ``sign`` when given)."""
    chosen = (table.target == at) & (True if sign is None else table.sign == sign)
    rows = [str(k + 1) for k in np.flatnonzero(chosen.to_numpy())]
    shown = ", ".join(rows[:5]) + (", …" if len(rows) > 5 else "")
    return f"row{'s' if len(rows) > 1 else ''} {shown}"


def _near_note(targets, at: float) -> str:
    """`` (… mm from target T mm: a mistyped target?)`` when another target lies within :data:`NEAR_TARGET_MM`."""
    others = np.asarray([t for t in targets if t != at], dtype=float)
    if not others.size:
        return ""
    nearest = float(others[np.argmin(np.abs(others - at))])
    if abs(nearest - at) >= NEAR_TARGET_MM:
        return ""
    return f" ({abs(nearest - at):.3g} mm from target {nearest:.15g} mm: a mistyped target?)"


def simulate_runs(
    targets_mm: Sequence[float],
    *,
    repeats: int = STANDARD_REPEATS,
    slope_um_per_m: float = 8.0,
    curvature_um: float = 3.0,
    pitch_um: float = 0.8,
    pitch_mm: float = 40.0,
    reversal_um: float = 4.0,
    noise_um: float = 0.5,
    drift_um_per_run: float = 0.2,
    seed: int = 0,
) -> pd.DataFrame:
    """Bidirectional positioning runs of a ball-screw axis, as ISO 230-2's standard test cycle reads them.

    Run j moves up through the targets, then down; the deviation at a target
    is a slope of the screw, a bow (``curvature_um`` at the ends relative to
    the middle), a periodic pitch error, half the reversal value ahead in the
    ↑ direction and behind in ↓, a drift growing by ``drift_um_per_run`` per
    run (the axis warming) and white noise. Deterministic under ``seed``.
    Columns: ``run``, ``direction`` (+/-), ``target_mm``, ``deviation_um``.
    """
    targets = np.sort(np.asarray(targets_mm, dtype=float))
    rng = np.random.default_rng(seed)
    middle, half = 0.5 * (targets[0] + targets[-1]), max(0.5 * (targets[-1] - targets[0]), 1e-12)
    systematic = (
        slope_um_per_m * targets / 1000.0
        + curvature_um * ((targets - middle) / half) ** 2
        + pitch_um * np.sin(2 * np.pi * targets / pitch_mm)
    )
    rows = []
    for j in range(repeats):
        for sign, order in ((1, targets), (-1, targets[::-1])):
            base = np.interp(order, targets, systematic) + sign * 0.5 * reversal_um + drift_um_per_run * j
            values = base + noise_um * rng.standard_normal(len(order))
            rows.extend((j + 1, "+" if sign > 0 else "-", float(p), float(v)) for p, v in zip(order, values))
    return pd.DataFrame(rows, columns=["run", "direction", "target_mm", "deviation_um"])


__all__ = [
    "Iso230Result",
    "STANDARD_REPEATS",
    "TARGET_LIMIT_MM",
    "direction_sign",
    "evaluate",
    "load_runs",
    "simulate_runs",
]
