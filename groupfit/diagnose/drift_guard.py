"""The null effect every candidate must be told from: a straight drift over the run.

A probe creeping, a foundation settling, a drift nobody logged: over one
modelling run, a long low-pass of anything that rises with the run follows
such a line, on the held-out conditions too, and is no effect. When the line
itself explains the held-out error (``min_score`` of it) and a candidate does
no better by more than one standard error, the two are told apart by scoring
the candidate once more, over the model *with* the line: an effect the next
run shares still removes ``min_score`` of what the line leaves (a heat source
switched on and off, which no straight line follows); a trend of the
modelling run removes next to nothing of it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from groupfit.diagnose.candidates import Candidate, score_candidate, within_one_se
from groupfit.features import Feature
from groupfit.heldout.scorer import HeldOutScorer


@dataclass
class DriftGuard:
    """A straight drift scored as the candidates are, and the candidates scored over the model with it.

    Parameters
    ----------
    ramp : ndarray
        Time since the start of each run, on the scored rows.
    scorer : HeldOutScorer
        The model's held-out scorer, on the same rows.
    values_of : callable
        ``values_of(candidate) -> ndarray``: a candidate's values on the same rows.
    name : str
        The time column, to name the drift.
    """

    ramp: np.ndarray
    scorer: HeldOutScorer
    values_of: Callable[[Candidate], np.ndarray]
    name: str = "time"
    null: Candidate = field(init=False)
    _with_drift: HeldOutScorer | None = field(init=False, default=None, repr=False)

    def __post_init__(self) -> None:
        self.null = score_candidate(Feature(self.name), self.ramp, self.scorer)

    def over_drift(self, candidate: Candidate) -> Candidate:
        """``candidate`` scored as one more regressor of the model with the drift among its regressors."""
        if self._with_drift is None:
            self._with_drift = self.scorer.with_regressor(self.ramp)
        return score_candidate(candidate.feature, self.values_of(candidate), self._with_drift)

    def refusal(self, candidate: Candidate, min_score: float, *, as_good=within_one_se) -> str | None:
        """Why ``candidate`` cannot be told from the drift; None when it can, or the drift explains too little.

        ``as_good(a, b)``: whether the folds cannot tell a's held-out error from b's.
        """
        if self.null.score < min_score or not as_good(self.null, candidate):
            return None
        beyond = self.over_drift(candidate)
        if beyond.score >= min_score:
            return None
        return (
            f"a straight drift over the run explains the held-out error as well (score {self.null.score:.2f}), "
            f"and over the model with that drift the effect removes {100 * max(beyond.score, 0.0):.0f} % of what "
            f"is left ({100 * min_score:.0f} % needed): it cannot be told from a drift of the modelling run "
            "(a probe creeping?)"
        )
