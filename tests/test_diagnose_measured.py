"""The diagnosis on real measured data: a CNC spindle step-speed test (``../shared/data``, skipped when absent)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.modelfile import model_to_dict
from groupfit.models.grouped import GroupedRegressor
from groupfit.switching import replay_groups

MEASURED = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
SENSORS = [f"t{k}_C" for k in range(1, 17)]
pytestmark = pytest.mark.skipif(not MEASURED.is_file(), reason=f"measured data not present at {MEASURED}")


def split_runs(frame, first, last):
    """The test with rows [first, last) held out: the modelling runs before and after, and the held-out run."""
    parts = [frame.iloc[:first], frame.iloc[last:]]
    runs = [
        load_run(p.reset_index(drop=True), temps=SENSORS, error="disp_ch3_um", name=f"part{k}")
        for k, p in enumerate(parts)
        if len(p)
    ]
    held = load_run(frame.iloc[first:last].reset_index(drop=True), temps=SENSORS, error="disp_ch3_um", name="held_out")
    return runs, held


def sixteen_sensor_model(runs):
    X = np.vstack([r.temps for r in runs])
    y = np.concatenate([r.error for r in runs])
    from dataclasses import replace

    joined = replace(runs[0], temps=X, error=y, time=np.arange(len(y)) * runs[0].period)
    return model_to_dict(GroupedRegressor(p=0).fit(X, y), joined)


@pytest.fixture(scope="module")
def frame():
    return pd.read_csv(MEASURED)


def test_spindle_speed_is_the_effect_named_first(frame):
    run = load_run(frame, temps=SENSORS, error="disp_ch3_um", name="spindle_step_test")
    result = diagnose(sixteen_sensor_model([run]), run, live_rule=replay_groups)
    assert result.folds.startswith("leave-one-condition-out over 7 operating segments")
    assert result.base_check["overfitted"]  # 16 collinear sensors: the warning is given
    assert result.candidates[0].feature.column == "spindle_rpm"
    assert result.added and result.added[0].feature.column == "spindle_rpm"
    assert result.added[0].feature.exponent == pytest.approx(5 / 3)


@pytest.mark.parametrize("block", [(31, 1951), (1951, 3871), (3871, 5791)], ids=["1250", "2500", "3750"])
def test_a_held_out_speed_block_is_judged_honestly(frame, block):
    runs, held = split_runs(frame, *block)
    result = diagnose(sixteen_sensor_model(runs), runs, held, live_rule=replay_groups)
    assert result.candidates[0].feature.column == "spindle_rpm"
    before, after = result.before["validate"]["rms_um"], result.after["validate"]["rms_um"]
    if result.added:
        assert result.improved is (after < before)
    else:
        assert result.improved is None and after == before
