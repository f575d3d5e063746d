"""The AR(1) model's expected next-run error: forward chaining over its heat column, in fit, replay and compare."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.ar1.fitting import fit_ar1_file
from groupfit.ar1.nextrun import ar1_forward_chaining, expect_ar1, file_predictor
from groupfit.cli import main
from groupfit.heldout.calibration import FACTOR, RATIO_RANGE, UNSEEN_CONDITION_FACTOR

C1 = 0.98
C2 = {0.0: 0.0, 1000.0: 0.05, 2000.0: 0.10, 3000.0: 0.15}
"""C2 grows in proportion to the heat (exponent 1): a model with the heat law's 5/3 misjudges an unseen level."""
BLOCK = 60
LEVELS = [0.0, 1000.0, 2000.0, 0.0, 1000.0, 2000.0, 3000.0, 0.0, 3000.0, 2000.0]
"""Ten blocks of 60 samples, each a new level: the segments are the blocks (none shorter than 3 % of the run
or longer than a sixth); the six from sample 240 on are scored, and 3000 is first seen at sample 360."""


def exact_run(levels=LEVELS, c2=C2):
    heat = np.repeat(levels, BLOCK)
    error = np.zeros(len(heat))
    for k in range(1, len(heat)):
        error[k] = C1 * error[k - 1] + c2[heat[k]]
    return heat, error


def free_run(heat, c2, n):
    out = np.zeros(n)
    for k in range(1, n):
        out[k] = C1 * out[k - 1] + c2[heat[k]]
    return out


def expected_raw_rms(heat, error, exponent=5 / 3):
    """By hand: every scored segment but the one at 360 is predicted exactly (its prefix saw all its levels, and
    the run is noise-free); there the prefix's model scales C2(2000) to 3000 by (3000 / 2000)^exponent."""
    seen = {**C2, 3000.0: C2[2000.0] * 1.5**exponent}
    start, end = 6 * BLOCK, 7 * BLOCK
    miss = error[start:end] - free_run(heat, seen, end)[start:end]
    return float(np.sqrt(np.sum(miss**2) / (6 * BLOCK)))


def fit_options(**changes):
    return {
        "period_s": 15.0,
        "heat_name": "speed_rpm",
        "error_name": "error_um",
        "source": "run",
        **changes,
    }


def test_each_scored_segment_is_predicted_by_the_model_of_the_run_before_it():
    heat, error = exact_run()
    options = fit_options()
    predict = file_predictor(heat, error, lambda q, e: fit_ar1_file(q, e, **options).model)
    scores = ar1_forward_chaining(heat, error, predict, heat_name="speed_rpm")
    assert scores.n_folds == 6 and scores.counts.tolist() == [BLOCK] * 6
    assert scores.n_conditions == len(set(LEVELS)) and not scores.blocks_of_time
    np.testing.assert_allclose(scores.raw_rms()[0], expected_raw_rms(heat, error), rtol=1e-9)
    assert expected_raw_rms(heat, error) > 0.1  # the unseen level is a real miss, not rounding


def test_a_run_whose_prefixes_saw_every_level_expects_nothing_beyond_rounding():
    heat, error = exact_run(levels=[0.0, 1000.0, 2000.0, 3000.0, 0.0, 2000.0, 1000.0, 3000.0, 0.0, 1000.0])
    options = fit_options()
    predict = file_predictor(heat, error, lambda q, e: fit_ar1_file(q, e, **options).model)
    assert ar1_forward_chaining(heat, error, predict, heat_name="speed_rpm").raw_rms()[0] < 1e-9


def test_a_cool_down_after_one_warm_up_keeps_the_panels_factor_for_the_physics_model():
    heat, error = exact_run(levels=[2000.0] * 5 + [0.0] * 5)  # a warm-up, then a cool-down from half the run
    options = fit_options()
    predict = file_predictor(heat, error, lambda q, e: fit_ar1_file(q, e, **options).model)
    expectation = expect_ar1(heat, error, predict, heat_name="speed_rpm")
    assert expectation.scores.leaves_one_condition and not expectation.scores.unseen_condition
    raw = float(expectation.scores.raw_rms()[0])
    assert expectation.expected()[0] == pytest.approx(FACTOR * raw, rel=1e-12)
    assert FACTOR != UNSEEN_CONDITION_FACTOR and "warm-up/cool-down runs" not in expectation.method()
    assert any("the heat law carries the physics model there" in note for note in expectation.notes)


def test_a_heat_column_that_never_changes_is_cut_into_blocks_of_time_and_says_so(tmp_path, capsys):
    heat = np.full(600, 2000.0)
    error = free_run(heat, C2, 600)
    path = tmp_path / "steady.csv"
    pd.DataFrame({"time_s": 15.0 * np.arange(600), "speed_rpm": heat, "error_um": error}).to_csv(path, index=False)
    assert main(["fit", "--model", "ar1", "--data", str(path), "--heat", "speed_rpm", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "equal blocks, no operating column" in out and "one run of one operating condition" in out


def write_run(path: Path, heat, error) -> Path:
    frame = pd.DataFrame({"time_s": 15.0 * np.arange(len(heat)), "speed_rpm": heat, "error_um": error})
    frame["T1"] = 20.0 + 0.1 * error  # compare needs a temperature
    frame.to_csv(path, index=False)
    return path


def test_fit_prints_records_and_replay_places_the_next_run_against_the_figure(tmp_path, capsys):
    heat, error = exact_run()
    run = write_run(tmp_path / "run.csv", heat, error)
    raw = expected_raw_rms(heat, error)
    args = ["fit", "--model", "ar1", "--data", str(run), "--heat", "speed_rpm", "--out", str(tmp_path / "m")]
    assert main([*args, "--json", str(tmp_path / "fit.json")]) == 0
    assert f"expect  about {FACTOR * raw:.3g} µm RMS on the next run" in capsys.readouterr().out
    fitted = json.loads((tmp_path / "fit.json").read_text())
    model = json.loads((tmp_path / "m" / "model.json").read_text())
    assert fitted["expected_next_run_rms_um"] == pytest.approx(FACTOR * raw, rel=1e-9)
    assert fitted["expected_next_run_range_um"] == pytest.approx([r * FACTOR * raw for r in RATIO_RANGE])
    assert model["training"]["expected_next_run_rms_um"] == fitted["expected_next_run_rms_um"]
    assert "forward chaining over 6 operating segments" in model["training"]["expected_next_run_method"]

    following = [2000.0, 0.0, 3000.0, 1000.0, 0.0, 2000.0]
    next_heat, next_error = exact_run(levels=following, c2={**C2, 3000.0: 0.2})  # a next run off the model
    next_run = write_run(tmp_path / "next.csv", next_heat, next_error)
    replay = ["replay", str(tmp_path / "m" / "model.json"), "--json", str(tmp_path / "r.json")]
    assert main([*replay, "--data", str(next_run)]) == 0
    result = json.loads((tmp_path / "r.json").read_text())
    check = result["expected_next_run"]
    assert check["actual_rms_um"] == pytest.approx(result["rms_um"]) and result["rms_um"] > 0.1
    assert check["actual_over_expected"] == pytest.approx(result["rms_um"] / fitted["expected_next_run_rms_um"])
    assert "expected about" in capsys.readouterr().out
    assert main([*replay, "--data", str(run)]) == 0
    assert json.loads((tmp_path / "r.json").read_text())["expected_next_run"]["place"] == "modelling run"


def test_a_model_file_whose_figure_lies_outside_its_range_is_refused(tmp_path, capsys):
    heat, error = exact_run()
    run = write_run(tmp_path / "run.csv", heat, error)
    assert main(["fit", "--model", "ar1", "--data", str(run), "--heat", "speed_rpm", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "model.json").read_text())
    data["training"]["expected_next_run_range_um"] = [0.0, 0.0]
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["replay", str(broken), "--data", str(run)]) == 2
    err = capsys.readouterr().err
    assert str(broken) in err and "training.expected_next_run_range_um" in err


def test_compare_expects_the_ar1_model_with_its_own_settings(tmp_path, capsys):
    heat, error = exact_run()
    run = write_run(tmp_path / "run.csv", heat, error)
    config = tmp_path / "compare.toml"
    config.write_text('[compare]\nheat = "speed_rpm"\nheat_exponent = 1.25\n')
    args = ["compare", str(config), "--data", str(run), "--temps", "T1", "--out", str(tmp_path / "c")]
    assert main([*args, "--pmax", "1", "--json", str(tmp_path / "c.json")]) == 0
    assert "AR(1) expected next-run RMS from run alone" in capsys.readouterr().out
    ar1 = json.loads((tmp_path / "c.json").read_text())["expected_next_run"]["ar1"]
    # compare's free run starts from the first measured error, 0 here, as fit's does
    expected = FACTOR * expected_raw_rms(heat, error, exponent=1.25)
    assert ar1["expected_next_run_rms_um"] == pytest.approx(expected, rel=1e-9)

    rise = '[compare]\nheat = "speed_rpm"\nar1_scaling = "rise"\nrise_sensor = "T1"\nrise_window_s = {}\n'
    config.write_text(rise.format(3000.0))
    assert main([*args, "--pmax", "1", "--json", str(tmp_path / "c.json")]) == 0
    assert json.loads((tmp_path / "c.json").read_text())["expected_next_run"]["ar1"] is None
    config.write_text(rise.format(150.0))  # T1 has not moved yet: no ratio can be taken against it
    capsys.readouterr()
    assert main([*args, "--pmax", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "rise sensor 'T1' rises by 0 over the first 150 s" in err
