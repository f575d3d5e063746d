import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from groupfit.errors import InputError
from groupfit.grouping import (
    Constraints,
    hard_groups,
    min_group_size,
    served_ranges,
    serving_group_index,
    soft_groups,
)


def test_groups_follow_the_paper_convention():
    # N = 20, breaks 6 and 13, soft offset 2
    assert hard_groups([6, 13], 20) == [(1, 6), (7, 13), (14, 20)]
    assert soft_groups([6, 13], 20, 2) == [(1, 6), (5, 13), (12, 20)]
    assert served_ranges([6, 13], 20, 2) == [(1, 4), (5, 11), (12, 20)]


def test_serving_index_matches_served_ranges_and_extends_past_the_run():
    index = serving_group_index([6, 13], 20, 2, length=25)
    expected = [0] * 4 + [1] * 7 + [2] * 9 + [2] * 5
    assert index.tolist() == expected


@pytest.mark.parametrize("c, M, size", [(3, 5, 16), (3.0, 4, 13), (2.5, 5, 13), (2.4, 5, 13), (1.25, 4, 6)])
def test_min_group_size_is_strictly_more_than_c_times_M(c, M, size):
    assert min_group_size(c, M) == size
    assert size > c * M and size - 1 <= c * M


@pytest.mark.parametrize("c, M, n, size", [(0, 3, 0, 4), (0.5, 5, 0, 6), (0, 1, 0, 2), (3, 5, 20, 21), (3, 5, 15, 16)])
def test_every_group_stays_over_determined_and_longer_than_n_whatever_c(c, M, n, size):
    assert min_group_size(c, M, n) == size
    assert size > M and size > n


@settings(max_examples=80, deadline=None)
@given(N=st.integers(2, 24), n=st.integers(0, 5), h=st.integers(5, 9))
def test_max_breaks_matches_enumeration(N, n, h):
    # with h >= 5 no more than 3 breaks fit in 24 samples, so p <= 4 covers every case
    constraints = Constraints(N, n, h)
    feasible = [
        p for p in range(0, 5) if any(constraints.is_feasible(b) for b in itertools.combinations(range(1, N), p))
    ]
    assert constraints.max_breaks() == (max(feasible) if feasible else -1)


def test_require_names_the_largest_feasible_p():
    constraints = Constraints.for_model(60, 3, 3.0, 5)
    with pytest.raises(InputError, match="the largest feasible p is 2"):
        constraints.require(3, 3.0, 5)


def test_feasibility_includes_first_and_last_group():
    constraints = Constraints(40, 3, 10)
    assert constraints.is_feasible([10, 20, 30])
    assert not constraints.is_feasible([9, 20, 30])
    assert not constraints.is_feasible([10, 20, 31])
    assert not constraints.is_feasible([10, 19, 30])
    assert not Constraints(40, 12, 10).is_feasible([12, 25])
    assert np.all([constraints.is_feasible([]), not Constraints(5, 0, 6).is_feasible([])])
