import numpy as np
import pytest

from groupfit.errors import InputError
from groupfit.heldout.selection import correlation_clusters, select_sensors


def smooth_noise(rng, n_samples, width=15):
    """Slowly varying, zero-mean signals like temperatures (moving average of white noise)."""
    kernel = np.ones(width) / width
    return np.convolve(rng.normal(size=n_samples + width), kernel, mode="valid")[:n_samples]


def planted_problem(seed=0, n_samples=400):
    """Twelve independent candidates, two near copies of T3; the error depends on T3 and T7 only."""
    rng = np.random.default_rng(seed)
    columns = {f"T{i}": smooth_noise(rng, n_samples) for i in range(12)}
    columns["T3_copy_a"] = columns["T3"] + 1e-3 * rng.normal(size=n_samples)
    columns["T3_copy_b"] = columns["T3"] + 1e-3 * rng.normal(size=n_samples)
    y = 2.0 * columns["T3"] - 1.5 * columns["T7"] + 0.02 * rng.normal(size=n_samples)
    names = list(columns)
    return np.column_stack([columns[n] for n in names]), y, names


@pytest.mark.parametrize("method", ["forward", "lasso"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_planted_sensors_are_found(method, seed):
    X, y, names = planted_problem(seed)
    chosen = select_sensors(X, y, names, method, 2)
    assert len(chosen) == 2
    assert "T7" in chosen
    assert {c for c in chosen if c != "T7"} <= {"T3", "T3_copy_a", "T3_copy_b"}


def test_forward_selection_does_not_pick_two_copies_of_one_sensor():
    X, y, names = planted_problem(0)
    chosen = select_sensors(X, y, names, "forward", 3)
    assert sum(c.startswith("T3") for c in chosen) == 1


def test_cluster_selection_takes_one_sensor_from_each_group():
    rng = np.random.default_rng(5)
    sources = [smooth_noise(rng, 300) for _ in range(3)]
    columns, group_of = [], []
    for g, source in enumerate(sources):
        for _ in range(4):
            columns.append(source + 0.05 * rng.normal(size=300))
            group_of.append(g)
    X = np.column_stack(columns)
    y = sources[0] + sources[1] + sources[2]
    names = [f"S{i}" for i in range(X.shape[1])]
    labels = correlation_clusters(X, n_clusters=3)
    assert len(set(labels)) == 3
    assert all(len({labels[i] for i in range(12) if group_of[i] == g}) == 1 for g in range(3))
    chosen = select_sensors(X, y, names, "cluster", 3)
    assert sorted(group_of[names.index(c)] for c in chosen) == [0, 1, 2]


def test_selection_is_deterministic_and_checks_k():
    X, y, names = planted_problem(3)
    assert select_sensors(X, y, names, "lasso", 4) == select_sensors(X, y, names, "lasso", 4)
    assert len(set(select_sensors(X, y, names, "lasso", 13))) == 13
    with pytest.raises(InputError, match="k = 20"):
        select_sensors(X, y, names, "forward", 20)
