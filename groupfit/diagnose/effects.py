"""The effect loop's parts: which candidates are tried, how one step ranks them, and which one it takes.

A cause is preferred to a symptom: an unused temperature sensor is added
only when no cause column (an ambient, a speed, a heat source's on/off)
passes. Among low-passes of the same column that pass, the shortest time
constant whose held-out error is within one standard error of the best
one's is taken (the one-standard-error rule of cross-validation): a longer
lag than the data need turns an effect into a trend of the modelling run.
Other columns that explain the held-out error as well as the one added
(within one standard error) are reported as alternatives.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from groupfit.columns import is_ambient_name, is_sensor_column
from groupfit.diagnose.candidates import EXOGENOUS_R, Candidate, candidate_features, rank_candidates
from groupfit.diagnose.drift_guard import DriftGuard
from groupfit.diagnose.notes import AMBIENT, SCOPE, Note
from groupfit.diagnose.policy import AcceptancePolicy, Stage
from groupfit.diagnose.problem import Problem, exogenous_sensors
from groupfit.diagnose.reference import droppable_reference
from groupfit.diagnose.result import Refused
from groupfit.features import Feature
from groupfit.heldout.scorer import HeldOutScorer


@dataclass(frozen=True)
class Choice:
    """What one step of the effect loop took (``best``, or None), refused on the way, and found as good."""

    best: Candidate | None
    refused: tuple[Refused, ...]
    alternatives: tuple[Candidate, ...]


@dataclass(frozen=True)
class Tried:
    """The candidate features and the columns read as machine sensors (symptoms, not causes)."""

    features: list[Feature]
    sensor_columns: frozenset[str]


def tried_features(
    problem: Problem, model_temps: Sequence[str], *, ambient: tuple[str, ...], heat_exponent, own_transforms: bool
) -> tuple[Tried, list[Note]]:
    """Every candidate feature of the problem's columns, and the notes on how the columns were read."""
    notes = []
    if not own_transforms:
        notes.append(
            Note(SCOPE, "transforms of the model's own inputs not tried (they re-weight what the model reads)")
        )
    columns, operating = problem.columns, problem.operating
    sensor_columns = frozenset(c for c in columns if is_sensor_column(c) and c not in ambient)
    air_named = any(is_ambient_name(c) or c in ambient for c in columns)
    if sensor_columns and operating and not air_named:
        exogenous = exogenous_sensors(problem.data, sorted(sensor_columns), operating, problem.period)
        for column in exogenous:
            notes.append(
                Note(
                    AMBIENT,
                    f"'{column}' is read as an ambient: no column is named as one, and it does not follow the heat "
                    f"sources ({', '.join(operating)}; |r| < {EXOGENOUS_R} with every lag)",
                )
            )
        sensor_columns -= set(exogenous)
        air_named = bool(exogenous)
    if sensor_columns and not air_named:
        unused = ", ".join(sorted(sensor_columns))
        notes.append(
            Note(
                AMBIENT,
                f"no column is named as an ambient (T_amb, ambient_C, T_room, air…): the unused sensors ({unused}) "
                "were read as machine sensors, tried as measured only; if one of them reads the air, say so with "
                "--ambient COLUMN and its lags are tried as well",
            )
        )
    features = candidate_features(
        columns,
        problem.measured_inputs if own_transforms else [],
        problem.frame(),
        operating,
        heat_exponent,
        sensor_transforms=own_transforms,
        sensor_columns=sensor_columns,
    )
    return Tried(features, sensor_columns), notes


def ranking(problem: Problem, model, inputs: list[np.ndarray], scorer: HeldOutScorer, tried: list[Feature]):
    """The candidates scored against the model, best first; lags of its reference column also taken over it."""
    rows = problem.measured
    model_inputs_now = np.vstack(inputs)[rows]
    ranked = rank_candidates(
        problem.target[rows], tried, problem.values, scorer, model_inputs_now, set(problem.measured_inputs)
    )
    over = droppable_reference(model, problem.data)
    lags_of_reference = [f for f in tried if f.column == over and f.transform in ("lowpass", "delay")]
    if lags_of_reference:  # a part lagging the air, read over the air as the model reads its sensors
        taken_over = rank_candidates(
            problem.target[rows], lags_of_reference, lambda f: problem.values(f, over), scorer, model_inputs_now
        )
        ranked = sorted(ranked + [replace(c, over=over) for c in taken_over], key=lambda c: -c.rank)
    return ranked


def choose(
    ranked: list[Candidate],
    policy: AcceptancePolicy,
    stage: Stage,
    *,
    sensor_columns: frozenset[str] = frozenset(),
    drift: DriftGuard | None = None,
) -> Choice:
    """The candidate to add, the refusals on the way, and other columns that explain the error as well.

    The best *cause* that passes its test — an ambient, a speed, a heat
    source's on/off, any column but the machine's temperature sensors — then
    the shortest adequate low-pass of its family. An unused temperature
    sensor is a symptom of some cause, not an effect: it is added only when
    no cause passes (a better sensor set is the job of ``fit --select``).
    """
    refused = []
    passing = []
    for candidate in ranked:
        if not policy.significant(candidate, stage):
            break
        refusal = policy.refusal(candidate, stage, drift)
        if refusal is not None:
            if not passing:
                refused.append(Refused(candidate, refusal))
            continue
        passing.append(candidate)
    if not passing:
        return Choice(None, tuple(refused), ())
    causes = [c for c in passing if c.feature.column not in sensor_columns]
    best = causes[0] if causes else passing[0]
    chosen = shortest_adequate_lag(best, [c for c in passing if c.family() == best.family()], policy)
    alternatives, seen = [], {chosen.feature.column}
    for c in passing:
        if c.feature.column not in seen and policy.as_good_as(c, passing[0]):
            alternatives.append(c)
            seen.add(c.feature.column)
    return Choice(chosen, tuple(refused), tuple(alternatives))


def shortest_adequate_lag(best: Candidate, family: list[Candidate], policy: AcceptancePolicy) -> Candidate:
    """The shortest low-pass of ``family`` whose held-out error the folds cannot tell from ``best``'s."""
    if best.feature.transform != "lowpass":
        return best
    adequate = [best, *(c for c in family if c.feature.transform == "lowpass" and policy.as_good_as(c, best))]
    return min(adequate, key=lambda c: c.feature.tau_s)
