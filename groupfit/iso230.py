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
it is not met, not refused.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import pandas as pd

from groupfit.data import numeric_column, read_table
from groupfit.errors import InputError

STANDARD_REPEATS = 5
"""Approaches per target and direction in ISO 230-2's standard test cycle."""
UP_WORDS = ("+", "up", "1", "+1", "pos", "positive", "forward", "↑")
DOWN_WORDS = ("-", "down", "-1", "neg", "negative", "backward", "↓")


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
    """The ISO 230-2 result of deviations ``up``, ``down`` (n runs × m targets, µm)."""
    up, down = np.asarray(up, dtype=float), np.asarray(down, dtype=float)
    targets = np.asarray(targets_mm, dtype=float)
    if up.shape != down.shape or up.ndim != 2 or up.shape[1] != len(targets):
        raise InputError(f"deviations of shape {up.shape} and {down.shape} for {len(targets)} targets")
    if up.shape[0] < 2:
        raise InputError(f"{up.shape[0]} run(s) per direction: the repeatability needs at least 2 (ISO 230-2: 5)")
    order = np.argsort(targets, kind="stable")
    return Iso230Result(targets_mm=targets[order], up=up[:, order], down=down[:, order])


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


def load_runs(
    source, *, target: str = "target_mm", direction: str = "direction", deviation: str = "deviation_um"
) -> Iso230Result:
    """Read bidirectional positioning runs (a long table, module docstring) and evaluate them.

    Each target's approaches in one direction are taken in the order of the
    rows (run 1 first). Refused with the file, column and row: a missing
    column, a non-numeric target or deviation, a direction that is neither,
    a target approached in one direction only or unequally often.
    """
    frame, _, label = read_table(source)
    for name in (target, direction, deviation):
        if name not in frame.columns:
            raise InputError(
                f"{label}: column '{name}' not found (target position mm, direction +/-, deviation um); "
                f"the columns are: {', '.join(map(str, frame.columns))}"
            )
    targets = numeric_column(frame, target, label, allow_nonfinite=False)
    deviations = numeric_column(frame, deviation, label, allow_nonfinite=False)
    signs = np.array([direction_sign(v) for v in frame[direction]])
    if np.any(signs == 0):
        row = int(np.flatnonzero(signs == 0)[0])
        raise InputError(
            f"{label}: row {row + 2}, column '{direction}': {frame[direction].iloc[row]!r} is no direction; "
            "write + or - (up/down, 1/-1)"
        )
    table = pd.DataFrame({"target": targets, "sign": signs, "deviation": deviations})
    counts = table.groupby(["target", "sign"]).size().unstack(fill_value=0)
    for sign, word in ((1, "positive"), (-1, "negative")):
        if sign not in counts.columns or (counts[sign] == 0).any():
            missing = counts.index[counts.get(sign, pd.Series(0, index=counts.index)) == 0]
            raise InputError(
                f"{label}: target {missing[0]:g} mm is never approached in the {word} direction; ISO 230-2 "
                "approaches every target from both sides"
            )
    repeats, most = int(counts.to_numpy().min()), int(counts.to_numpy().max())
    if most != repeats:
        at, sign = counts.stack().idxmin()
        raise InputError(
            f"{label}: target {at:g} mm is approached {repeats} time(s) in the {'+' if sign > 0 else '-'} "
            f"direction, up to {most} elsewhere: give every target the same number of runs each way"
        )
    positions = counts.index.to_numpy(dtype=float)
    up, down = (
        np.column_stack([table.deviation[(table.target == p) & (table.sign == sign)].to_numpy() for p in positions])
        for sign in (1, -1)
    )
    if len(positions) < 2:
        raise InputError(f"{label}: one target position only; ISO 230-2 evaluates an axis at several")
    try:
        return evaluate(up, down, positions)
    except InputError as exc:
        raise InputError(f"{label}: {exc}") from None


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


__all__ = ["Iso230Result", "STANDARD_REPEATS", "direction_sign", "evaluate", "load_runs", "simulate_runs"]
