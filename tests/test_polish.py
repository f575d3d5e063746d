"""The GA's closing local search on long runs: coarse to fine, against an exhaustive search."""

import numpy as np
import pytest

from groupfit.grouping import Constraints
from groupfit.objective import SegmentCost
from groupfit.search import polish
from groupfit.search.ga import CachedObjective


def long_run(n_samples: int, seed: int, regimes: int = 4):
    """Smooth temperature walks, an error linear in them whose coefficients change in ``regimes`` stretches."""
    rng = np.random.default_rng(seed)
    walks = np.cumsum(np.convolve(rng.normal(size=n_samples + 40), np.ones(40) / 40, "valid")[:n_samples], axis=0)
    X = np.column_stack([walks, np.cumsum(rng.normal(size=n_samples)) * 0.05, np.sin(np.arange(n_samples) / 300)])
    regime = np.minimum(np.arange(n_samples) * regimes // n_samples, regimes - 1)
    beta = rng.normal(size=(regimes, X.shape[1]))
    return X, np.einsum("nk,nk->n", X, beta[regime]) + 0.05 * rng.normal(size=n_samples)


def polished(X, y, start, *, objective="sae", exhaustive=False, monkeypatch=None):
    cost = SegmentCost(X, y, n=3, objective=objective)
    constraints = Constraints.for_model(len(y), 3, 3.0, cost.n_coef)
    if exhaustive:
        monkeypatch.setattr(polish, "COARSE_POSITIONS", 10**9)
    search = CachedObjective(cost)
    return polish.polish_breaks(list(start), search.totals([list(start)])[0], search, constraints), cost, constraints


def test_one_break_on_a_long_run_lands_where_every_position_tried_puts_it():
    X, y = long_run(6000, seed=3, regimes=2)
    (breaks, value), cost, constraints = polished(X, y, [900])
    assert polish.shift_range([900], 0, constraints)[1] - 900 > 4 * polish.COARSE_POSITIONS  # coarse to fine
    positions = np.arange(constraints.lowest_break, constraints.highest_break + 1)
    every = CachedObjective(cost).totals([[int(b)] for b in positions])
    assert value == pytest.approx(min(every), rel=1e-12)
    assert breaks == [int(positions[int(np.argmin(every))])]


@pytest.mark.parametrize("seed, start", [(0, [700, 1500, 4100]), (1, [2500, 2600, 2700]), (2, [400, 3900, 4400])])
def test_three_breaks_reach_the_optimum_of_the_exhaustive_local_search(seed, start, monkeypatch):
    X, y = long_run(4800, seed=seed)
    (coarse, coarse_value), _, _ = polished(X, y, start, objective="sse")
    (full, full_value), _, _ = polished(X, y, start, objective="sse", exhaustive=True, monkeypatch=monkeypatch)
    assert coarse == full
    assert coarse_value == pytest.approx(full_value, rel=1e-12)
