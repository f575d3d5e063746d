"""The error to expect on the next run: folds that imitate a new run, scored through the run-time rule.

A model's in-run held-out figures (:mod:`groupfit.heldout.check`) refit on the
samples around the held-out ones; a next run gives the model no such help. The
estimate here scores each candidate model only on data that comes *after* what
it was fitted on, served as a controller serves it:

* two or more runs: leave-one-run-out. The global model (p = 0, the only model
  fitted on several runs) is fitted on the other runs and replayed over the
  held-out one.
* one run: forward chaining over operating segments. The run is cut into its
  operating segments (:mod:`groupfit.heldout.folds`: where an operating column
  such as the spindle speed changes, else equal blocks of time). For every
  segment k that starts after :data:`MIN_TRAIN_FRACTION` of the run, each
  candidate is fitted on the run up to the start of segment k, the prefix and
  segment k are replayed through the run-time rule (the group switched by the
  model's own rule, its state carried from the first sample) and only segment k
  is scored. The squared errors are pooled over the segments.

A long run is thinned to at most :data:`MAX_SAMPLES` rows for the estimate (the
break search is the exact one, on Σe², whose cost grows with N²); the figure is
a raw one, calibrated by :mod:`groupfit.heldout.calibration`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from groupfit.clamped_scores import within_compensation_clamp
from groupfit.columns import aligned_inputs
from groupfit.data import Run, join_runs
from groupfit.grouping import Constraints
from groupfit.heldout.choice import pooled_error
from groupfit.heldout.folds import fold_columns, make_folds, setting_values
from groupfit.models.grouped import GroupedRegressor
from groupfit.objective import SegmentCost
from groupfit.runtime import replay_groups
from groupfit.runtime.rule import compensation_clamp
from groupfit.search.exact import solve_exact

MAX_SAMPLES = 600
"""A run longer than this is thinned (every k-th row) for the estimate."""
PHASES = 3
"""A thinned run is scored from this many first rows spread over one stride, the squared errors pooled: which
rows one thinning kept moved a grouped candidate's estimate by a factor of up to 2-4 (docs/nextrun.md)."""
MIN_TRAIN_FRACTION = 0.4
"""Forward chaining scores the segments that start after this share of the run."""
MIN_SEGMENTS = 3
"""Fewer scored segments than this make the estimate a rough one (a note says so)."""
NO_OPERATING_COLUMN = "no operating column"
FORWARD = "forward"
LEAVE_ONE_RUN_OUT = "leave-one-run-out"


@dataclass(frozen=True)
class NextRunScores:
    """Squared errors of every candidate on folds that imitate a next run.

    ``sse[i, k]`` and ``counts[k]``: candidate ``i``'s sum of squared errors on
    fold ``k`` and the samples scored there. ``kind`` is :data:`FORWARD` or
    :data:`LEAVE_ONE_RUN_OUT`.
    """

    candidates: tuple
    sse: np.ndarray
    counts: np.ndarray
    kind: str
    segments: str
    """How the folds were cut (operating columns, blocks of time, runs)."""
    stride: int = 1
    n_samples: int = 0
    """Samples of the (thinned) run the folds were cut from."""
    n_conditions: int = 0
    """Distinct operating conditions in the run (1 with no operating column; 0: not counted)."""
    blocks_of_time: bool = False
    """The scored folds are equal blocks of time, not operating segments."""
    leaves_one_condition: bool = False
    """A scored segment starts a condition the run before it has not seen, that run holding one condition alone
    (:func:`leaves_one_condition`)."""
    unfitted_runs: tuple = ()
    """Runs left out of the folds: the others, trained on without them, hold fewer samples than ``fit`` takes."""
    physics_model: bool = False
    """The scores are the AR(1) physics model's (:mod:`groupfit.ar1.nextrun`), whose forward chaining through a
    cool-down after one warm-up follows the heat law and keeps the panel's factor."""

    @property
    def unseen_condition(self) -> bool:
        """Whether the figure takes the factor of a run whose scored segment starts a condition the run before it
        never saw (:data:`groupfit.heldout.calibration.UNSEEN_CONDITION_FACTOR`)."""
        return self.leaves_one_condition and not self.physics_model

    @property
    def n_folds(self) -> int:
        return int(self.sse.shape[1])

    def raw_rms(self) -> np.ndarray:
        """Each candidate's pooled RMS over the folds (µm)."""
        return np.sqrt(self.sse.sum(axis=1) / self.counts.sum())

    def pooled(self) -> tuple[np.ndarray, np.ndarray]:
        """Each candidate's pooled mean squared error and its standard error over the folds."""
        return pooled_error(self.sse, self.counts)

    def standard_error(self) -> np.ndarray:
        """Standard error of each candidate's pooled mean squared error, from its spread over the folds."""
        return self.pooled()[1]

    def method(self) -> str:
        """One line on how the estimate was made."""
        if self.kind == LEAVE_ONE_RUN_OUT:
            runs = f"{self.n_folds} run{'s' if self.n_folds != 1 else ''}"
            return f"leave-one-run-out over {runs}, each replayed through the run-time rule"
        phases = len(phase_offsets(self.stride))
        thinned = f", one sample in {self.stride}, {phases} thinnings pooled" if self.stride > 1 else ""
        folds = "blocks of time" if self.blocks_of_time else "operating segments"
        return (
            f"forward chaining over {self.n_folds} {folds} ({self.segments}{thinned}): fitted on the "
            "run before each segment, replayed through the run-time rule, scored on the segment"
        )


def thinning_stride(n_samples: int, max_samples: int = MAX_SAMPLES) -> int:
    """k, the least whole number for which every k-th row leaves at most ``max_samples`` of ``n_samples`` rows."""
    return max(1, int(np.ceil(n_samples / max_samples)))


def sliced(run: Run, rows: np.ndarray, *, period: float | None = None) -> Run:
    """The run restricted to ``rows`` (indices or a slice), as a run of its own."""
    return dataclasses.replace(
        run,
        time=run.time[rows],
        temps=run.temps[rows],
        error=None if run.error is None else run.error[rows],
        frame=run.frame.iloc[rows].reset_index(drop=True),
        period=run.period if period is None else period,
    )


def segment_starts(run: Run) -> tuple[list[int], str, int, bool, np.ndarray | None]:
    """First sample of every operating segment of ``run`` (0-based), how they were found, how many distinct
    operating conditions the run holds (a condition the run returns to counts once), whether the segments are
    equal blocks of time (the run has no operating column), and each sample's condition (one code per
    combination of the operating columns' levels; None for blocks of time)."""
    exclude = {run.time_name, run.error_name, *run.temp_names}
    if run.reference not in (None, "start"):
        exclude.add(run.reference)
    folds = make_folds([run.frame], fold_columns(run.frame, exclude))
    labels = folds.labels
    starts = [0, *(np.flatnonzero(np.diff(labels) != 0) + 1).tolist()]
    if folds.kind == "condition":
        values = np.column_stack([setting_values(run.frame, c) for c in folds.columns])
        distinct, codes = np.unique(values, axis=0, return_inverse=True)
        if len(distinct) == 1:  # cut into pieces of time, as a run without the columns is
            constant = f"the run cut into {len(starts)} blocks, {', '.join(folds.columns)} never changing"
            return starts, constant, 1, True, None
        return starts, f"changes of {', '.join(folds.columns)}", len(distinct), False, codes.reshape(-1)
    return starts, f"the run cut into {len(starts)} equal blocks, {NO_OPERATING_COLUMN}", 1, True, None


def forward_folds(run: Run, starts: Sequence[int], min_train: float = MIN_TRAIN_FRACTION) -> list[tuple[int, int]]:
    """``(start, end)`` of the segments scored by forward chaining: those starting after ``min_train`` of the run."""
    n = run.n_samples
    edges = [*starts, n]
    return [(a, b) for a, b in zip(edges[:-1], edges[1:]) if a >= min_train * n and b > a]


def leaves_one_condition(folds: Sequence[tuple[int, int]], codes: np.ndarray | None) -> bool:
    """Whether a scored segment starts a condition its run before has not seen, that run holding one condition
    alone (a cool-down scored on a model of the warm-up): every candidate extrapolates there."""
    if codes is None:
        return False
    return any(codes[a] not in codes[:a] and len(np.unique(codes[:a])) == 1 for a, _ in folds)


def feasible_pmax(n_samples: int, *, n: int, c: float, n_coef: int, pmax: int) -> int:
    """The largest p ≤ ``pmax`` whose groups fit in ``n_samples`` samples (-1: not even p = 0)."""
    constraints = Constraints.for_model(n_samples, n, c, n_coef)
    best = -1
    for p in range(pmax + 1):
        try:
            constraints.require(p, c, n_coef)
        except Exception:
            break
        best = p
    return best


def rule_prediction(
    estimator: GroupedRegressor, fitted_on: Run, temps: np.ndarray, criterion: str | None = None
) -> np.ndarray:
    """What a controller compensates over ``temps`` from sample 1 on: the group chosen by the model's rule, with
    its bumpless transfer after a switch, within the clamp the rule sets from ``fitted_on`` (as ``replay``
    scores it). ``criterion``: the rule's switching sensor (default: the input that moves most)."""
    if estimator.p == 0 and not estimator.breaks_:
        clamp = compensation_clamp(estimator.intercept_[0] + fitted_on.temps @ estimator.coef_[0])
        return np.clip(estimator.intercept_[0] + temps @ estimator.coef_[0], -clamp, clamp)
    model = estimator.to_model_file(fitted_on, criterion)
    prediction = model.predict(temps, replay_groups(model, temps), transfer=True)  # with the bumpless transfer
    return within_compensation_clamp(prediction, model.switching)


def forward_chaining(
    run: Run,
    p_values: Sequence[int],
    *,
    n: int = 3,
    c: float = 3.0,
    fit_intercept: bool = True,
    ridge_alpha: float = 0.0,
    max_samples: int = MAX_SAMPLES,
    min_train: float = MIN_TRAIN_FRACTION,
    shared: np.ndarray | None = None,
    criterion: str | None = None,
) -> NextRunScores:
    """Every p of ``p_values`` scored by forward chaining over ``run``'s operating segments (module docstring).

    The breaks of each prefix are the exact optimum of Σe² for every p at once;
    the groups are fitted by least squares (a global model, p = 0, with the
    ridge penalty ``ridge_alpha``). A p whose groups do not fit in the shortest
    prefix is left out of ``candidates``. ``shared`` marks the inputs with one
    coefficient for every group (a diagnosis's effects,
    :func:`groupfit.heldout.design.shared_columns`): the breaks are sought on
    the others, as the model's were before the effects were added, and the
    groups fitted with them shared; ``criterion``: the rule's switching sensor.
    """
    stride = thinning_stride(run.n_samples, max_samples)
    settings = (p_values, n, c, fit_intercept, ridge_alpha, min_train)
    phases = [
        _phase_scores(thinned_from(run, stride, offset), *settings, shared=shared, criterion=criterion)
        for offset in phase_offsets(stride)
    ]
    candidates = tuple(p for p in phases[0][0] if all(p in phase[0] for phase in phases))
    if len({phase[1].shape[1] for phase in phases}) == 1:  # the same folds in every phase: pooled fold by fold
        sse = sum(phase[1][[phase[0].index(p) for p in candidates]] for phase in phases)
        counts = sum(phase[2] for phase in phases)
    else:
        sse = np.hstack([phase[1][[phase[0].index(p) for p in candidates]] for phase in phases])
        counts = np.concatenate([phase[2] for phase in phases])
    _, _, _, how, conditions, blocks, n_thin, leaves = phases[0]
    return NextRunScores(candidates, sse, counts, FORWARD, how, stride, n_thin, conditions, blocks, leaves)


def phase_offsets(stride: int, phases: int = PHASES) -> list[int]:
    """The first rows of the thinned runs the estimate pools: up to ``phases`` spread over one stride."""
    count = min(phases, stride)
    return sorted({k * stride // count for k in range(count)})


def thinned_from(run: Run, stride: int, offset: int) -> Run:
    """Every ``stride``-th row of ``run`` from row ``offset`` (the run itself for a stride of 1)."""
    if stride == 1:
        return run
    return sliced(run, np.arange(offset, run.n_samples, stride), period=run.period * stride)


def _phase_scores(thin: Run, p_values, n, c, fit_intercept, ridge_alpha, min_train, *, shared=None, criterion=None):
    """Forward chaining on one thinned run: candidates, sse, counts, how, conditions, blocks, samples, and
    whether a scored segment leaves the one condition of the run before it."""
    own = None if shared is None or not np.any(shared) else ~np.asarray(shared, dtype=bool)
    starts, how, conditions, blocks, codes = segment_starts(thin)
    folds = forward_folds(thin, starts, min_train)
    if not folds:  # no segment starts late enough: score the run's last blocks of time
        folds = forward_folds(thin, _blocks(thin.n_samples), min_train)
        how, blocks = f"{how}; none starts after {100 * min_train:g} % of the run, its last blocks scored", True
    n_coef = thin.temps.shape[1] + int(fit_intercept)
    shortest = min(a for a, _ in folds)
    top = feasible_pmax(shortest, n=n, c=c, n_coef=n_coef, pmax=max(p_values))
    candidates = tuple(p for p in p_values if p <= top)
    if not candidates:
        tried = ", ".join(str(p) for p in p_values)
        raise ValueError(f"no model of p = {tried} fits in the {shortest} samples before the first scored segment")
    sse = np.zeros((len(candidates), len(folds)))
    counts = np.zeros(len(folds))
    X, y = thin.temps, thin.error
    for k, (start, end) in enumerate(folds):
        prefix = sliced(thin, slice(0, start))
        searched = prefix if own is None else dataclasses.replace(prefix, temps=prefix.temps[:, own])
        breaks = prefix_breaks(searched, max(candidates), n=n, c=c, fit_intercept=fit_intercept)
        scored = slice(start, end)
        counts[k] = end - start
        for i, p in enumerate(candidates):
            estimator = candidate_estimator(
                p, breaks[p], n=n, c=c, fit_intercept=fit_intercept, ridge_alpha=ridge_alpha, shared=shared
            )
            estimator.fit(prefix.temps, prefix.error)
            prediction = rule_prediction(estimator, prefix, X[:end], criterion if p else None)
            sse[i, k] = float(np.sum((y[scored] - prediction[scored]) ** 2))
    return candidates, sse, counts, how, conditions, blocks, thin.n_samples, leaves_one_condition(folds, codes)


def prefix_breaks(prefix: Run, pmax: int, *, n: int, c: float, fit_intercept: bool) -> dict[int, list[int]]:
    """The exact Σe² optimum of every p up to ``pmax`` on ``prefix`` (p = 0: no break)."""
    if pmax == 0:
        return {0: []}
    cost = SegmentCost(prefix.temps, prefix.error, n=n, objective="sse", fit_intercept=fit_intercept)
    n_coef = prefix.temps.shape[1] + int(fit_intercept)
    result = solve_exact(cost, Constraints.for_model(prefix.n_samples, n, c, n_coef), pmax)
    return {p: list(b) for p, b in result.breaks.items()}


def candidate_estimator(
    p: int,
    breaks: Sequence[int],
    *,
    n: int,
    c: float,
    fit_intercept: bool,
    ridge_alpha: float = 0.0,
    shared: np.ndarray | None = None,
) -> GroupedRegressor:
    """The model of p breaks at ``breaks`` (groups by least squares, the ``shared`` inputs with one coefficient
    for every group; p = 0 with the ridge penalty)."""
    if p == 0:
        return GroupedRegressor(p=0, n=n, c=c, objective="sse", fit_intercept=fit_intercept, ridge_alpha=ridge_alpha)
    return GroupedRegressor(
        p=p,
        n=n,
        c=c,
        objective="sse",
        fit_intercept=fit_intercept,
        fixed_breaks=list(breaks),
        shared_columns=None if shared is None else [bool(v) for v in shared],
    )


def next_run_splits(runs: Sequence[Run]) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(train, test)`` row indices of the runs laid end to end, for a global model (p = 0), whose rule is trivial.

    Several runs: each run held out, the others trained on. One run: forward chaining, the run before each
    scored segment trained on (:func:`forward_folds`).
    """
    lengths = [r.n_samples for r in runs]
    edges = np.cumsum([0, *lengths])
    if len(runs) > 1:
        rows = np.arange(edges[-1])
        return [
            (np.r_[rows[: edges[k]], rows[edges[k + 1] :]], rows[edges[k] : edges[k + 1]]) for k in range(len(runs))
        ]
    starts, *_ = segment_starts(runs[0])
    folds = forward_folds(runs[0], starts) or forward_folds(runs[0], _blocks(runs[0].n_samples))
    return [(np.arange(a), np.arange(a, b)) for a, b in folds]


def _blocks(n_samples: int) -> list[int]:
    return list(np.linspace(0, n_samples, 7).astype(int)[:-1])


def leave_one_run_out(
    runs: Sequence[Run], *, fit_intercept: bool = True, ridge_alpha: float = 0.0, min_train: int = 0
) -> NextRunScores:
    """The global model (p = 0) fitted on all runs but one and replayed over that one, for every run (the
    inputs matched by name). A run whose others hold fewer than ``min_train`` measured samples (what ``fit``
    takes for the model) is not held out: no user could fit on the others alone (``unfitted_runs``)."""
    runs = aligned_inputs(list(runs))
    sse, counts, unfitted = [], [], []
    for k, held_out in enumerate(runs):
        others = join_runs([r for j, r in enumerate(runs) if j != k])
        rows = np.isfinite(others.error)
        if rows.sum() < min_train:
            unfitted.append(held_out.name)
            continue
        scored = np.isfinite(held_out.error)
        estimator = candidate_estimator(0, [], n=0, c=0.0, fit_intercept=fit_intercept, ridge_alpha=ridge_alpha)
        estimator.fit(others.temps[rows], others.error[rows])
        prediction = rule_prediction(estimator, others, held_out.temps)
        sse.append(float(np.sum((held_out.error[scored] - prediction[scored]) ** 2)))
        counts.append(int(scored.sum()))
    if not sse:
        raise ValueError("no run can be held out: the others are too short to fit on")
    return NextRunScores(
        (0,),
        np.array([sse]),
        np.array(counts, dtype=float),
        LEAVE_ONE_RUN_OUT,
        f"{len(sse)} runs",
        1,
        int(sum(counts)),
        unfitted_runs=tuple(unfitted),
    )


__all__ = [
    "FORWARD",
    "LEAVE_ONE_RUN_OUT",
    "MAX_SAMPLES",
    "MIN_SEGMENTS",
    "MIN_TRAIN_FRACTION",
    "NextRunScores",
    "forward_chaining",
    "forward_folds",
    "leave_one_run_out",
    "next_run_splits",
    "rule_prediction",
    "segment_starts",
    "thinned_from",
    "thinning_stride",
]
