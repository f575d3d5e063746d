"""The bumpless transfer on the next run: a switch is no longer a jump of the difference of two groups' models.

A p = 3 model fitted on one run and replayed on another (the FE repeats; a
printer-like run B after run A) switches where the criterion says. With a hard
switch the prediction steps by many times its ordinary motion there; with the
transfer no step into a switch is larger than twice the largest other step
within 10 samples of it, and the jump is spread over the n + 1 steps of the
transfer (each a quarter of it at n = 3).
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
    hard = model.replace(switching=model.switching.with_rule({"blend_samples": 0}))
    blended = SwitchingRule(model).replay(next_run.temps)
    jumped = SwitchingRule(hard).replay(next_run.temps)
    assert np.array_equal(blended.group, jumped.group)  # the same decisions, only the output moves otherwise
    assert worst_switch_ratio(blended.prediction_um, blended.switched) <= 2.0
    assert worst_switch_ratio(jumped.prediction_um, jumped.switched) > 2.0  # the check can fail: hard switches do
