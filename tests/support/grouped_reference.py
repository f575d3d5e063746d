"""Least squares of a grouped model whose effects share one coefficient, written out with numpy for the tests."""

import numpy as np

from groupfit.grouping import serving_group_index, soft_groups


def shared_effect_fit(own, shared, y, breaks, n):
    """The shared coefficients and each soft group's own coefficients.

    ``own`` (N, k): each group's regressors (a column of ones for the intercept included); ``shared`` (N, m):
    one coefficient for every group. The shared ones come from one least-squares problem over the hard
    groups (each group its own copy of ``own``); each soft group is then fitted on ``y`` minus them.
    """
    serving = serving_group_index(breaks, len(y), n)
    blocks = [own * (serving == g)[:, None] for g in range(len(breaks) + 1)]
    gamma = np.linalg.lstsq(np.column_stack([*blocks, shared]), y, rcond=None)[0][-shared.shape[1] :]
    rest = y - shared @ gamma
    rows = [slice(first - 1, last) for first, last in soft_groups(breaks, len(y), n)]
    return gamma, [np.linalg.lstsq(own[r], rest[r], rcond=None)[0] for r in rows], rows
