"""The bumpless transfer on the next run: a switch is no longer a jump of the difference of two groups' models.

A p = 3 model fitted on one run and replayed on another (the FE repeats; a
printer-like run B after run A) switches where the criterion says. With a hard
switch the prediction steps by many times its ordinary motion there; with the
transfer no step into a switch is larger than twice the largest other step
within 10 samples of it: the output starts from the last output before the
switch and closes its gap to the new group's prediction by one share of
n + 1 per sample (a quarter at n = 3), whatever the two groups' models do,
also when the groups lie far apart and the inputs are noisy.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_real_logs import cycle_means

from groupfit.data import load_run
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor
from groupfit.runtime import SwitchingRule
from groupfit.search.base import SearchSettings

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


def fitted(run, p: int = 3) -> ModelFile:
    search = SearchSettings(method="exact", seed=0)
    return ModelFile.coerce(
        GroupedRegressor.from_settings(p=p, n=3, search=search).fit(run.temps, run.error).to_model_file(run)
    )


def worst_switch_ratio(prediction: np.ndarray, switched: np.ndarray) -> float:
    """Largest step into a switch sample over the largest other step within 10 samples of it."""
    steps = np.abs(np.diff(prediction))
    ratios = []
    for s in np.flatnonzero(switched):
        near = [steps[k] for k in range(max(s - 11, 0), min(s + 10, len(steps))) if k != s - 1]
        ratios.append(steps[s - 1] / max(near))
    assert ratios, "the rule switched nowhere: nothing to check"
    return max(ratios)


def hard(model: ModelFile) -> ModelFile:
    return model.replace(switching=model.switching.with_rule({"blend_samples": 0}))


def runs():
    yield (
        load_run(DATASETS / "paper_cycle.csv", temps=["T1", "T2"]),
        load_run(DATASETS / "repeat_ambient25.csv", temps=["T1", "T2"]),
    )
    yield (
        load_run(DATASETS / "paper_cycle.csv", temps=["T1", "T2"]),
        load_run(DATASETS / "validation_speed.csv", temps=["T1", "T2"]),
    )
    yield (
        load_run(cycle_means(seed=1), temps=["T1", "T2"], name="A"),
        load_run(cycle_means(seed=7, shift=40), temps=["T1", "T2"], name="B"),
    )


@pytest.mark.parametrize("pair", list(runs()), ids=["FE ambient 25", "FE other speed", "printer-like A -> B"])
def test_no_switch_steps_by_more_than_twice_the_steps_around_it(pair):
    modelling, next_run = pair
    model = fitted(modelling)
    assert model.switching.blend_samples == 3
    blended = SwitchingRule(model).replay(next_run.temps)
    jumped = SwitchingRule(hard(model)).replay(next_run.temps)
    assert np.array_equal(blended.group, jumped.group)  # the same decisions, only the output moves otherwise
    assert worst_switch_ratio(blended.prediction_um, blended.switched) <= 2.0
    assert worst_switch_ratio(jumped.prediction_um, jumped.switched) > 2.0  # the check can fail: hard switches do


def apart(model: ModelFile, scale: float) -> ModelFile:
    """The model with its groups ``scale`` times further apart: group g's coefficients are group 1's plus
    ``scale`` times their own difference from group 1's, and its constant ``scale`` µm × (-1)^g more."""
    coefficients = np.asarray(model.coefficients, dtype=float)
    spread = coefficients[0] + scale * (coefficients - coefficients[0])
    spread[:, 0] += scale * (-1.0) ** np.arange(len(spread))
    return model.replace(coefficients=tuple(tuple(row) for row in spread.tolist()))


@pytest.mark.parametrize("scale, noise_c", [(1.0, 0.05), (10.0, 0.0), (10.0, 0.05), (30.0, 0.1)])
def test_groups_far_apart_and_noisy_inputs_keep_every_switch_within_twice_the_steps_around(scale, noise_c):
    modelling, next_run = next(runs())
    model = apart(fitted(modelling), scale)
    temps = next_run.temps + np.random.default_rng(3).normal(0.0, noise_c, next_run.temps.shape)
    blended = SwitchingRule(model).replay(temps)
    jumped = SwitchingRule(hard(model)).replay(temps)
    assert worst_switch_ratio(blended.prediction_um, blended.switched) <= 2.0
    assert worst_switch_ratio(jumped.prediction_um, jumped.switched) > 2.0


@pytest.mark.parametrize("precision", ["double", "single"])
def test_the_transfer_closes_the_gap_from_the_last_output_by_one_share_per_sample(precision):
    """Closed form against the hard switch's replay (the new group's own prediction): from a switch at s,
    output[s + k] = hard[s + k] + (n - k) / (n + 1) · (output[s - 1] - hard[s]) for k < n, the hard
    prediction from s + n on; elsewhere the two agree exactly."""
    modelling, next_run = next(runs())
    model = apart(fitted(modelling), 10.0)
    n = model.switching.blend_samples
    blended = SwitchingRule(model, precision=precision).replay(next_run.temps)
    jumped = SwitchingRule(hard(model), precision=precision).replay(next_run.temps)
    expected = jumped.prediction_um.copy()
    for s in np.flatnonzero(blended.switched):
        gap = blended.prediction_um[s - 1] - jumped.prediction_um[s]
        for k in range(n):
            expected[s + k] = jumped.prediction_um[s + k] + (n - k) / (n + 1) * gap
    tolerance = 1e-4 if precision == "single" else 1e-9
    assert np.flatnonzero(blended.switched).size >= 2
    np.testing.assert_allclose(blended.prediction_um, expected, rtol=0, atol=tolerance)
