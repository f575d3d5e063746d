"""A modelling log split into files that continue one another: the derived inputs are those of the whole log."""

import numpy as np
import pytest
from support.diagnose_scenarios import global_model
from test_diagnose_on_time import spindle_run

from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.notes import HISTORY, UNSCORED
from groupfit.diagnose.residual import residual
from groupfit.runtime import replay_groups

TEMPS = ["T1", "T2", "T3"]
SCHEDULE = [(5000, 3000), (3000, 0), (6000, 5000), (4000, 0), (4000, 2000), (3000, 0), (8000, 4000), (5000, 0)]


def test_a_split_log_is_diagnosed_with_the_history_of_the_files_before():
    log = spindle_run(SCHEDULE, 3)
    whole = load_run(log, temps=TEMPS, name="whole")
    cuts = [0, 200, 450, len(log)]  # each file after the first starts with the spindle at speed, the machine hot
    parts = [load_run(log.iloc[a:b], temps=TEMPS, name=f"part{k + 1}") for k, (a, b) in enumerate(zip(cuts, cuts[1:]))]
    assert log["speed_rpm"].iloc[200] > 0 and log["speed_rpm"].iloc[450] > 0
    model = global_model(whole)

    result = diagnose(model, parts, live_rule=replay_groups)
    assert result.added and result.added[0].feature.start == "rest"
    assert result.folds == "leave-one-run-out over 3 runs"
    # the augmented model on the parts, as scored and refitted, is the augmented model on the whole log
    on_whole = residual(result.model, whole, replay_groups)
    np.testing.assert_allclose(result.residuals_after["data"], on_whole, rtol=0, atol=1e-9)
    # and the refit is the least-squares fit on the whole log with the effect computed on it
    effect = result.added[0].feature.compute(log[result.added[0].feature.column].to_numpy(float), 60.0)
    design = np.column_stack([np.ones(len(log)), log[TEMPS].to_numpy(float), effect])
    coefficients, *_ = np.linalg.lstsq(design, log["error_um"].to_numpy(float), rcond=None)
    assert np.asarray(result.model.coefficients)[0] == pytest.approx(coefficients, rel=1e-6, abs=1e-9)
    assert [n.split(" (")[0] for n in result.notes_of(HISTORY) if " continues " in n] == [
        "part2 continues part1",
        "part3 continues part2",
    ]
    assert not result.notes_of(UNSCORED)
