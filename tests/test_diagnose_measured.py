"""The diagnosis on real measured data: a CNC spindle step-speed test (``../shared/data``, skipped when absent)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.diagnose_scenarios import global_model

from groupfit.data import load_run, measured_rows
from groupfit.diagnose import diagnose
from groupfit.diagnose.notes import HISTORY
from groupfit.diagnose.policy import FOLD_WORSENED
from groupfit.models.grouped import GroupedRegressor
from groupfit.runtime import replay_groups

MEASURED = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
SENSORS = [f"t{k}_C" for k in range(1, 17)]
pytestmark = pytest.mark.skipif(not MEASURED.is_file(), reason=f"measured data not present at {MEASURED}")


def split_runs(frame, first, last):
    """The whole test twice: the error of rows [first, last) left empty (modelling), and of every other row.

    Every row stays, so a low-pass of the speed keeps its history through the
    held-out block, as on the controller; only rows with an error are fitted or scored.
    """
    block = np.zeros(len(frame), dtype=bool)
    block[first:last] = True
    modelling, held = frame.copy(), frame.copy()
    modelling.loc[block, "disp_ch3_um"] = np.nan
    held.loc[~block, "disp_ch3_um"] = np.nan
    run = load_run(modelling, temps=SENSORS, error="disp_ch3_um", name="others", allow_nonfinite=True)
    return [run], load_run(held, temps=SENSORS, error="disp_ch3_um", name="held_out", allow_nonfinite=True)


def sixteen_sensor_model(runs):
    measured = measured_rows(runs[0])
    return global_model(measured)


@pytest.fixture(scope="module")
def frame():
    return pd.read_csv(MEASURED)


def test_spindle_speed_is_the_effect_named_first(frame):
    run = load_run(frame, temps=SENSORS, error="disp_ch3_um", name="spindle_step_test")
    result = diagnose(sixteen_sensor_model([run]), run, live_rule=replay_groups)
    assert result.folds.startswith("leave-one-condition-out over 7 operating segments")
    assert result.base_check.overfitted  # 16 collinear sensors: the warning is given
    assert result.candidates[0].feature.column == "spindle_rpm"
    assert result.added and result.added[0].feature.column == "spindle_rpm"
    assert result.added[0].feature.exponent == pytest.approx(5 / 3)


@pytest.mark.parametrize("block", [(31, 1951), (1951, 3871), (3871, 5791)], ids=["1250", "2500", "3750"])
def test_a_held_out_speed_block_is_judged_honestly(frame, block):
    runs, held = split_runs(frame, *block)
    base = sixteen_sensor_model(runs)
    result = diagnose(base, runs, held, live_rule=replay_groups)
    assert result.candidates[0].feature.column == "spindle_rpm"
    before, after = result.before["validate"]["rms_um"], result.after["validate"]["rms_um"]
    if result.added:
        assert result.improved is (after < before)
        assert result.summary().startswith("the augmented model is worse") is (after >= before)
    else:
        assert result.improved is None and after == before
    # the held-out block is scored on its own rows, its inputs' history run through the whole test
    prediction = GroupedRegressor.from_model_file(base).predict(held.temps)
    assert before == pytest.approx(np.sqrt(np.nanmean((held.error - prediction) ** 2)))


def test_an_effect_that_fits_the_other_speeds_at_the_cold_starts_expense_is_refused(frame):
    """With the 1250 r/min block held out the heat law wins the summed score but ruins the cold start."""
    runs, held = split_runs(frame, 31, 1951)
    result = diagnose(sixteen_sensor_model(runs), runs, held, live_rule=replay_groups)
    assert result.candidates[0].feature.column == "spindle_rpm" and result.candidates[0].score > 0.3
    assert not result.added and result.after == result.before
    assert FOLD_WORSENED in {refused.rule_id for refused in result.refused}
    first = result.summary().splitlines()[0]
    assert first.startswith("no effect added: the best candidate, spindle speed") and "was refused: makes one" in first


def test_joint_selection_on_the_whole_test_forecasts_less_than_the_given_model(frame):
    """Sensors and the heat law chosen together: fewer inputs, speed named, a nested forecast below the base's."""
    run = load_run(frame, temps=SENSORS, error="disp_ch3_um", name="spindle_step_test")
    result = diagnose(sixteen_sensor_model([run]), run, live_rule=replay_groups, select_jointly=True)
    assert result.added[0].feature.column == "spindle_rpm" and result.added[0].feature.exponent == pytest.approx(5 / 3)
    assert 1 <= len(result.selection.inputs) < len(SENSORS)
    assert result.selection.nested_held_out_rms_um < result.base_check.held_out_rms_um
    assert tuple(result.model.temps[: len(result.selection.inputs)]) == result.selection.inputs


def test_a_validation_file_that_continues_the_log_is_judged_with_its_history(frame):
    """The test cut in two files in the 5000 r/min block: from rest, the heat law's low-pass starts cold."""
    cut = int(0.9 * len(frame))
    first = load_run(frame.iloc[:cut].reset_index(drop=True), temps=SENSORS, error="disp_ch3_um", name="first")
    later = frame.iloc[cut:].reset_index(drop=True)
    model = sixteen_sensor_model([first])
    results = {}
    for gap_s in (0.0, 3600.0):
        shifted = later.assign(time_s=later["time_s"] + gap_s)
        second = load_run(shifted, temps=SENSORS, error="disp_ch3_um", name="second")
        results[gap_s] = diagnose(model, first, second, live_rule=replay_groups)
    continuing, restarted = results[0.0], results[3600.0]
    assert any(note.startswith("second continues first") for note in continuing.notes_of(HISTORY))
    assert continuing.added[0].feature.column == "spindle_rpm"
    assert continuing.improved is True and restarted.improved is False  # the same effect, judged two ways
    assert continuing.after["validate"]["rms_um"] < 0.7 * continuing.before["validate"]["rms_um"]
