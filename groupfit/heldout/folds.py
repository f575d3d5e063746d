"""Held-out folds that imitate the next run: one operating condition, or one run, at a time.

A candidate effect is worth adding only if it predicts data the model has
not seen *under another condition*. Contiguous blocks cut at arbitrary times
leave both sides of a block under the same condition, so a term that only
fits the modelling run's history (a slow drift, a long low-pass that tracks
the run's trend) scores as well as a real effect. The folds here are whole
operating segments:

* three or more runs given: each run is a fold (leave-one-run-out);
* one or two runs with operating columns (spindle speed, on/off of a heat source:
  piecewise-constant columns that move in steps): each stretch between two
  changes of any of them is a fold (leave-one-condition-out), a stretch
  shorter than :data:`MIN_FOLD_FRACTION` of the run joined to the one before,
  one longer than ``1 /`` :data:`FALLBACK_BLOCKS` of the run cut into equal
  pieces (a long equilibrium phase would otherwise leave too little to
  train on);
  (a run's start begins a new stretch);
* otherwise two runs are two folds, and one run is cut into
  :data:`FALLBACK_BLOCKS` contiguous blocks of time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from groupfit.columns import is_displacement, usable_columns
from groupfit.setting_levels import held_setting, is_setting, setting_levels

MIN_FOLD_FRACTION = 0.03
"""A condition segment shorter than this share of the run is joined to the one before."""
MIN_FOLDS = 3
MIN_RUNS = 3
"""Leave-one-run-out needs at least this many runs; with fewer, conditions inside the runs are held out."""
FALLBACK_BLOCKS = 6


@dataclass(frozen=True)
class Folds:
    """A fold label per sample and what the folds are."""

    labels: np.ndarray
    kind: str
    """``"run"``, ``"condition"`` or ``"block"``."""
    columns: tuple[str, ...] = ()
    """The operating columns the conditions were read from (kind ``"condition"``)."""
    scored: np.ndarray | None = None
    """Which samples are scored when their fold is held out (None: all). An unscored sample is neither
    fitted nor scored in its own fold, and fitted in the others (:meth:`within_groups`)."""

    @property
    def n_folds(self) -> int:
        scored = self.labels if self.scored is None else self.labels[self.scored]
        return len(np.unique(scored))

    @property
    def n_unscored(self) -> int:
        return 0 if self.scored is None else int(np.count_nonzero(~self.scored))

    def describe(self) -> str:
        if self.kind == "run":
            text = f"leave-one-run-out over {self.n_folds} runs"
        elif self.kind == "condition":
            text = f"leave-one-condition-out over {self.n_folds} operating segments (from {', '.join(self.columns)})"
        else:
            text = f"{self.n_folds} contiguous blocks of time (no operating column to cut conditions from)"
        if self.n_unscored:
            text += f"; {self.n_unscored} samples not scored: held out, their group keeps too few samples to be fitted"
        return text

    def splits(self, rows: np.ndarray | None = None):
        """``(train, test)`` boolean masks, one pair per fold with a scored sample, restricted to ``rows``."""
        rows = np.ones(len(self.labels), dtype=bool) if rows is None else rows
        scored = rows if self.scored is None else rows & self.scored
        for label in np.unique(self.labels[scored]):
            held_out = self.labels == label
            yield rows & ~held_out, scored & held_out

    def restricted(self, rows: np.ndarray) -> "Folds":
        """The same folds on the samples ``rows`` only (e.g. those with a measured error)."""
        return Folds(self.labels[rows], self.kind, self.columns, None if self.scored is None else self.scored[rows])

    def within_groups(self, groups: np.ndarray, min_samples: int) -> "Folds":
        """The folds of a grouped model, whose groups (``groups``, one label per sample) are fitted apart.

        A held-out sample is scored only when its group keeps more than ``min_samples`` samples outside
        the sample's fold: a fold that takes (nearly) all of a group leaves nothing to fit that group on,
        and the model is never asked to predict with a group it could not fit (the fit itself asks each
        group for more than c·M samples).
        """
        scored = np.ones(len(self.labels), dtype=bool)
        for label in np.unique(self.labels):
            held_out = self.labels == label
            for group in np.unique(groups[held_out]):
                if np.count_nonzero((groups == group) & ~held_out) <= min_samples:
                    scored[held_out & (groups == group)] = False
        if self.scored is not None:
            scored &= self.scored
        return Folds(self.labels, self.kind, self.columns, scored)

    def index_splits(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``(train, test)`` sample indices, one pair per fold (the scikit-learn ``cv`` form)."""
        return [(np.flatnonzero(train), np.flatnonzero(test)) for train, test in self.splits()]


def operating_columns(frame: pd.DataFrame, candidates: list[str]) -> list[str]:
    """Columns among ``candidates`` that look like operating settings: piecewise constant, few levels.

    A column constant at a value other than 0 is one too: a heater switched on at the start at its
    set-point (its lags start from rest). A setting read back with noise counts by its levels
    (:func:`setting_levels`).
    """
    found = []
    for column in candidates:
        values = held_setting(pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float))
        if values is None or (np.ptp(values) == 0.0 and values[0] == 0.0):
            continue
        if is_setting(values):
            found.append(column)
    return found


def setting_values(frame: pd.DataFrame, column: str) -> np.ndarray:
    """An operating column's values as the setting's levels, a missed reading held at the one before it."""
    values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
    held = held_setting(values)
    return setting_levels(values if held is None else held)


def fold_columns(frame: pd.DataFrame, exclude: set[str]) -> list[str]:
    """The columns the folds may read operating conditions from: those that can explain a residual
    (:func:`groupfit.columns.usable_columns`), and those left out of them only for a few missed readings that
    are operating settings once each missed reading is held (:func:`groupfit.setting_levels.held_setting`): a
    speed logged with one empty cell still marks the run's conditions."""
    usable, _ = usable_columns(frame, exclude)
    missed = [
        column
        for column in frame.columns
        if column not in exclude
        and column not in usable
        and not is_displacement(str(column))
        and not np.isfinite(pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)).all()
        and operating_columns(frame, [column])
    ]
    return [column for column in frame.columns if column in usable or column in missed]


def condition_segments(frame: pd.DataFrame, columns: list[str]) -> np.ndarray:
    """Segment label per sample: a new segment wherever any operating column changes."""
    n = len(frame)
    change = np.zeros(n, dtype=bool)
    for column in columns:
        change[1:] |= np.diff(setting_values(frame, column)) != 0
    starts = np.flatnonzero(change)
    min_length = max(2, int(np.ceil(MIN_FOLD_FRACTION * n)))
    kept = [0]
    for start in starts:
        if start - kept[-1] >= min_length:
            kept.append(int(start))
    if n - kept[-1] < min_length and len(kept) > 1:
        kept.pop()
    longest = int(np.ceil(n / FALLBACK_BLOCKS))
    starts = []
    for start, end in zip(kept, [*kept[1:], n]):
        pieces = int(np.ceil((end - start) / longest))
        starts.extend(np.linspace(start, end, pieces + 1).astype(int)[:-1].tolist())
    labels = np.zeros(n, dtype=int)
    for label, start in enumerate(starts):
        labels[start:] = label
    return labels


def block_labels(n: int, n_blocks: int = FALLBACK_BLOCKS) -> np.ndarray:
    edges = np.linspace(0, n, n_blocks + 1).astype(int)
    labels = np.zeros(n, dtype=int)
    for label, start in enumerate(edges[:-1]):
        labels[start:] = label
    return labels


def make_folds(frames: list[pd.DataFrame], candidate_columns: list[str]) -> Folds:
    """Folds over the samples of ``frames`` (stacked in order): by run, by condition, or by block."""
    lengths = [len(f) for f in frames]
    by_run = np.repeat(np.arange(len(frames)), lengths)
    if len(frames) >= MIN_RUNS:
        return Folds(by_run, "run")
    columns = [c for c in candidate_columns if all(c in f.columns for f in frames)]
    columns = operating_columns(pd.concat([f[columns] for f in frames], ignore_index=True), columns)
    if columns:
        offset, labels = 0, []
        for frame in frames:
            segment = condition_segments(frame, columns)
            labels.append(segment + offset)
            offset += int(segment.max()) + 1
        labels = np.concatenate(labels)
        if len(np.unique(labels)) >= MIN_FOLDS:
            return Folds(labels, "condition", tuple(columns))
    if len(frames) == 2:
        return Folds(by_run, "run")
    return Folds(block_labels(len(frames[0])), "block")
