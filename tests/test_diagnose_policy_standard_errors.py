"""The policy's one-standard-error rule: one threshold steers every "as good as" judgement of the diagnosis."""

from __future__ import annotations

import numpy as np
import pytest

from groupfit.diagnose.candidates import Candidate
from groupfit.diagnose.effects import shortest_adequate_lag
from groupfit.diagnose.policy import AcceptancePolicy
from groupfit.features import Feature


def lowpass(tau_s: float, fold_sse) -> Candidate:
    return Candidate(Feature("speed", "lowpass", tau_s=tau_s), 0.6, 1.0, 1.0, fold_sse=tuple(fold_sse))


def brute_force_within(candidate: Candidate, best: Candidate, k: float) -> bool:
    """Σd ≤ k·√K·sd(d) over the fold-by-fold differences d, written out term by term."""
    d = [a - b for a, b in zip(candidate.fold_sse, best.fold_sse)]
    mean = sum(d) / len(d)
    sd = (sum((x - mean) ** 2 for x in d) / (len(d) - 1)) ** 0.5
    return sum(d) <= k * len(d) ** 0.5 * sd


@pytest.mark.parametrize("k", [0.0, 0.5, 1.0, 2.0])
def test_as_good_as_is_the_sum_of_fold_differences_within_k_standard_errors(k):
    rng = np.random.default_rng(3)
    policy = AcceptancePolicy(as_good_standard_errors=k)
    for _ in range(200):
        best = lowpass(600.0, rng.uniform(1.0, 2.0, 6))
        other = lowpass(300.0, np.asarray(best.fold_sse) + rng.normal(0.1, 0.3, 6))
        assert policy.as_good_as(other, best) == brute_force_within(other, best, k)


def test_the_shortest_adequate_lag_follows_the_policy_threshold():
    best = lowpass(1800.0, [1.0, 1.0, 1.0, 1.0])
    shorter = lowpass(600.0, [1.05, 1.2, 0.95, 1.1])  # worse on the sum by 1.44 standard errors
    family = [best, shorter]
    assert shortest_adequate_lag(best, family, AcceptancePolicy()) is best
    assert shortest_adequate_lag(best, family, AcceptancePolicy(as_good_standard_errors=2.0)) is shorter
