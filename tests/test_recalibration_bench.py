"""The claims of ``bench/bench_recalibration.py`` on runs the model never saw: an independent simulator's next
day, and the measured spindle test cut into a modelling 40 % and the next 20 % (skipped without ../shared); and
what ``bench/bench_recalibration_choice.py`` counts."""

from __future__ import annotations

import numpy as np
import pytest
from support.bench_modules import load

bench = load("bench_recalibration")


def run_scenario(name, tmp_path):
    found = list(bench.scenarios_to_run([name], tmp_path))
    if not found:
        pytest.skip(f"{name}: its data is not here")
    ((label, model, frames, following, scored_from),) = found
    return bench.scenario_result(label, model, frames, following, scored_from)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["independent:speed_rpm_2h_30s", pytest.param("measured", marks=pytest.mark.measured)])
def test_checks_help_the_chosen_filter_beats_the_hold_and_a_gross_check_costs_little(tmp_path, name):
    result = run_scenario(name, tmp_path)
    assert bench.check_claims(result) == []
    table = result["rms_um"]
    assert all(a < 0.5 * n for a, n in zip(table["auto"], table["none"]))  # checks every ≤ 2 h halve the error
    if name == "measured":  # the drift earns its place here: better than the hold at 30 and 60 min
        assert table["auto"][2] < 0.97 * table["hold"][2] and table["auto"][3] < 0.93 * table["hold"][3]


choice = load("bench_recalibration_choice")


def test_the_choice_bench_compares_the_chosen_filter_with_the_hold_no_checks_hindsight_and_one_fixed_filter():
    def pair(none, candidates, chosen):
        cell = {"candidates": candidates, "chosen": candidates[chosen], "replay_chosen": candidates[chosen]}
        return {"none": none, "matches_file": True, "descriptions": ["offset hold", "a", "b"], "intervals": [cell]}

    # pair 1: chosen 20 % worse than the hold; pair 2: every candidate more than 5 % worse than no checks
    line = choice.summary([pair(1.0, [0.5, 0.6, 0.4], 1), pair(0.3, [0.4, 0.35, 0.33], 2)], 0, 1800.0)
    geo = lambda *ratios: f"{np.exp(np.mean(np.log(ratios))):.3f}"  # noqa: E731
    assert f"chosen {geo(1.2, 0.33 / 0.4)}" in line
    assert f"best fixed candidate (b) {geo(0.8, 0.33 / 0.4)}" in line
    assert f"hindsight best {geo(0.8, 0.33 / 0.4)}" in line
    assert "worse than the hold by > 5 %: 1, than no checks: 1" in line
    assert "no candidate better than no checks by 5 %: 1, every candidate worse than no checks by > 5 %: 1" in line
