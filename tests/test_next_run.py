"""The expected next-run error: forward chaining and leave-one-run-out against loops written out by hand."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run, measured_rows
from groupfit.grouping import Constraints
from groupfit.heldout import calibration
from groupfit.heldout.choice import one_standard_error_choice, pooled_error
from groupfit.heldout.expect import expect_next_run, trust_notes
from groupfit.heldout.folds import make_folds
from groupfit.heldout.nextrun import MIN_TRAIN_FRACTION, forward_chaining, leave_one_run_out, phase_offsets
from groupfit.model import ModelFile
from groupfit.model import model_file_problem as model_problem
from groupfit.models.grouped import GroupedRegressor
from groupfit.runtime import SwitchingRule

SEGMENT = 20
FIT_OPTIONS = ("--temps", "T1,T2", "--reference", "none", "--quiet", "--recalibrate", "none")
"""Without probe recalibration: its tuning needs runs longer than these two-hour ones."""
SPEEDS = (0, 1000, 2000, 1000, 0, 2000)


def tiny_frame(seed: int = 0, speeds=SPEEDS, segment: int = SEGMENT) -> pd.DataFrame:
    """Two temperatures driven by a stepped speed, an error that follows them with a drift and noise."""
    rng = np.random.default_rng(seed)
    speed = np.repeat(speeds, segment).astype(float)
    n = len(speed)
    t1 = 20 + np.cumsum(0.002 * speed / 1000 - 0.01 * rng.standard_normal(n)) + 0.02 * rng.standard_normal(n)
    t2 = 20 + 0.5 * np.cumsum(0.002 * speed / 1000) + 0.3 * np.sin(np.arange(n) / 7) + 0.02 * rng.standard_normal(n)
    error = 3.0 * (t1 - 20) - 2.0 * (t2 - 20) + 0.02 * np.arange(n) + 0.05 * rng.standard_normal(n)
    return pd.DataFrame({"time_s": 60.0 * np.arange(n), "T1": t1, "T2": t2, "speed_rpm": speed, "error_um": error})


def tiny_run(seed: int = 0, **kwargs):
    return load_run(tiny_frame(seed, **kwargs), name=f"tiny{seed}", temps=["T1", "T2"])


def best_breaks_by_brute_force(X, y, p, n_samples, *, c):
    """The least Σe² break vector of p ≤ 1 breaks (n = 0: soft groups are the hard groups), every position tried."""
    if p == 0:
        return []
    A = np.column_stack([np.ones(n_samples), X])
    constraints = Constraints.for_model(n_samples, 0, c, A.shape[1])
    best, best_sse = None, np.inf
    for b in range(constraints.lowest_break, constraints.highest_break + 1):
        sse = 0.0
        for rows in (slice(0, b), slice(b, n_samples)):
            coef, *_ = np.linalg.lstsq(A[rows], y[rows], rcond=None)
            sse += float(np.sum((y[rows] - A[rows] @ coef) ** 2))
        if sse < best_sse:
            best, best_sse = [b], sse
    return best


def test_forward_chaining_matches_a_loop_written_out_by_hand():
    run = tiny_run()
    c = 1.0
    scores = forward_chaining(run, [0, 1], n=0, c=c, fit_intercept=True)
    # the segments by hand: a new one where the speed changes, scored when it starts after 40 % of the run
    starts = [k * SEGMENT for k in range(len(SPEEDS))]
    scored = [(a, a + SEGMENT) for a in starts if a >= 0.4 * run.n_samples]
    assert scores.n_folds == len(scored) == 3 and scores.segments == "changes of speed_rpm"
    assert not scores.blocks_of_time and "operating segments" in scores.method()
    expected = np.zeros((2, len(scored)))
    for k, (start, end) in enumerate(scored):
        X, y = run.temps[:start], run.error[:start]
        for p in (0, 1):
            breaks = best_breaks_by_brute_force(X, y, p, start, c=c)
            model = GroupedRegressor(p=p, n=0, c=c, fixed_breaks=breaks or None, search="exact").fit(X, y)
            prefix = load_run(tiny_frame().iloc[:start], name="prefix", temps=["T1", "T2"])
            rule = SwitchingRule(model.to_model_file(prefix))  # the controller, from sample 1 to the segment's end
            prediction = rule.replay(run.temps[:end]).prediction_um
            expected[p, k] = np.sum((run.error[start:end] - prediction[start:end]) ** 2)
    assert scores.counts.tolist() == [SEGMENT] * 3
    np.testing.assert_allclose(scores.sse, expected, rtol=1e-9)
    np.testing.assert_allclose(scores.raw_rms(), np.sqrt(expected.sum(axis=1) / (3 * SEGMENT)), rtol=1e-9)


def write_runs(tmp_path, seeds):
    paths = []
    for seed in seeds:
        path = tmp_path / f"run{seed}.csv"
        tiny_frame(seed).to_csv(path, index=False)
        paths.append(str(path))
    return paths


def test_leave_one_run_out_matches_fit_and_replay_run_by_run(tmp_path, capsys):
    paths = write_runs(tmp_path, (1, 2, 3))
    sse, count, per_run = 0.0, 0, []
    for k, held_out in enumerate(paths):
        others = [p for j, p in enumerate(paths) if j != k]
        out = tmp_path / f"fit{k}"
        options = [*FIT_OPTIONS, "--p", "0"]
        assert main(["fit", "--data", *others, *options, "--out", str(out)]) == 0
        replayed = tmp_path / f"replay{k}.json"
        assert main(["replay", str(out / "model.json"), "--data", held_out, "--json", str(replayed)]) == 0
        residual = np.array([s["residual_um"] for s in json.loads(replayed.read_text())["samples"]], dtype=float)
        sse += float(np.nansum(residual**2))
        count += int(np.isfinite(residual).sum())
        per_run.append(float(np.sqrt(np.nanmean(residual**2))))
    capsys.readouterr()
    result = tmp_path / "all.json"
    options = [*FIT_OPTIONS, "--ridge", "0", "--out", str(tmp_path / "all")]  # least squares, as --p 0 above
    assert main(["fit", "--data", *paths, *options, "--json", str(result)]) == 0
    fitted = json.loads(result.read_text())
    assert fitted["p"] == 0
    # each held-out run is a real next run: not scaled by the one-run calibration
    assert fitted["expected_next_run_rms_um"] == pytest.approx(np.sqrt(sse / count), rel=1e-9)
    assert "leave-one-run-out over 3 runs" in fitted["expected_next_run_method"]
    low, high = fitted["expected_next_run_range_um"]  # the held-out runs' spread, at least the panel's band
    expected = fitted["expected_next_run_rms_um"]
    floor, ceiling = calibration.SEVERAL_RUNS_RANGE
    assert low == pytest.approx(min(min(per_run), floor * expected))
    assert high == pytest.approx(max(max(per_run), ceiling * expected))
    saved = ModelFile.load(tmp_path / "all" / "model.json").training
    assert saved["expected_next_run_rms_um"] == fitted["expected_next_run_rms_um"]


def test_leave_one_run_out_scores_each_run_with_the_others_fit():
    runs = [tiny_run(seed) for seed in (4, 5)]
    scores = leave_one_run_out(runs)
    for k in range(2):
        other = runs[1 - k]
        A = np.column_stack([np.ones(other.n_samples), other.temps])
        coef, *_ = np.linalg.lstsq(A, other.error, rcond=None)
        residual = runs[k].error - np.column_stack([np.ones(runs[k].n_samples), runs[k].temps]) @ coef
        assert scores.sse[0, k] == pytest.approx(float(residual @ residual), rel=1e-9)


def test_one_standard_error_rule_on_constructed_scores():
    # the best is the last; the second is within one of its standard errors, the first is not
    assert one_standard_error_choice([5.0, 3.0, 2.9, 2.8], [0.1, 0.1, 0.1, 0.25]) == 1
    assert one_standard_error_choice([5.0, 3.0, 2.9, 2.8], [0.1, 0.1, 0.1, 0.15]) == 2
    assert one_standard_error_choice([1.0, 3.0, 2.9], [0.0, 0.1, 0.1]) == 0  # the simplest is the best
    assert one_standard_error_choice([4.0, 2.0], [np.inf, np.inf]) == 1  # no spread known: the least
    with pytest.raises(ValueError):
        one_standard_error_choice([1.0, 2.0], [0.1])


def test_a_more_complex_model_must_beat_the_simpler_by_the_tolerance():
    # mean squared errors: p = 1's RMS is 1.6x below p = 0's, p = 2's 2.5x
    mean, se = [4.0, 1.5625, 0.64], [0.0, 0.0, 0.0]
    assert one_standard_error_choice(mean, se) == 2
    assert one_standard_error_choice(mean, se, rms_tolerance=2.0) == 1  # p = 1 is within a factor 2 of the best
    assert one_standard_error_choice(mean, se, rms_tolerance=2.6) == 0
    assert one_standard_error_choice([4.0, 0.9], [0.0, 0.0], rms_tolerance=2.0) == 1  # 2.1x better: taken
    assert one_standard_error_choice([5.0, 3.0, 2.8], [0.1, 0.1, 0.25], rms_tolerance=1.0) == 1  # the 1-SE rule
    with pytest.raises(ValueError):
        one_standard_error_choice([1.0], [0.0], rms_tolerance=0.5)


def test_pooled_error_is_the_weighted_mean_and_its_standard_error():
    sse = np.array([[4.0, 9.0, 1.0]])
    counts = np.array([2.0, 3.0, 1.0])
    pooled, se = pooled_error(sse, counts)
    mse = np.array([2.0, 3.0, 1.0])
    w = counts / counts.sum()
    assert pooled[0] == pytest.approx(sse.sum() / counts.sum())
    assert se[0] == pytest.approx(np.sqrt(np.sum(w * (mse - pooled[0]) ** 2) / 2))


def test_calibration_is_the_median_and_percentiles_of_the_ratios():
    raw = np.array([1.0, 2.0, 4.0, 1.0, 3.0])
    actual = np.array([2.0, 8.0, 4.0, 3.0, 3.0])
    derived = calibration.derive_calibration(raw, actual)
    factor = 2.0  # the ratios 2, 4, 1, 3, 1: the middle one of five
    assert derived["factor"] == pytest.approx(factor)
    assert derived["ratio_low"] == pytest.approx(0.5)  # ratios / 2: 0.5, 0.5, 1, 1.5, 2
    assert derived["ratio_high"] == pytest.approx(1.8)  # 90th percentile: 1.5 + 0.6 · (2 - 1.5)
    value, (low, high) = calibration.expected(2.0)
    assert value == pytest.approx(2.0 * calibration.FACTOR)
    assert low == pytest.approx(calibration.RATIO_RANGE[0] * value)
    assert high == pytest.approx(calibration.RATIO_RANGE[1] * value)


def test_a_run_without_operating_columns_is_noted_as_one_condition():
    frame = tiny_frame(7).drop(columns="speed_rpm")
    run = load_run(frame, name="one", temps=["T1", "T2"])
    scores = forward_chaining(run, [0])
    notes = trust_notes(scores)
    assert any("one run of one operating condition" in note and "record a run" in note for note in notes)
    # the folds are blocks of time, and the method says so rather than calling them operating segments
    blocks = len(np.unique(make_folds([frame], []).labels))
    scored = sum(start >= MIN_TRAIN_FRACTION * len(frame) for start in np.linspace(0, len(frame), blocks + 1)[:-1])
    assert scores.n_folds == scored and scores.blocks_of_time
    assert scores.method().startswith(f"forward chaining over {scored} blocks of time (the run cut into {blocks} ")
    assert "operating segments" not in scores.method()


def test_an_error_measured_on_every_tenth_row_keeps_the_operating_conditions():
    # a probe cycle every ten samples: the fit and its estimate see a tenth of the rows, the speed steps all
    frame = tiny_frame(12, segment=100)
    frame.loc[frame.index % 10 != 9, "error_um"] = np.nan
    run = load_run(frame, name="probed", temps=["T1", "T2"], missing_error=True)
    every_row = forward_chaining(tiny_run(12, segment=100), [0])
    probed = forward_chaining(measured_rows(run), [0])
    assert probed.segments == every_row.segments == "changes of speed_rpm"
    assert probed.n_conditions == every_row.n_conditions == len(set(SPEEDS))
    assert not any("one operating condition" in note for note in trust_notes(probed))


def test_too_few_conditions_are_noted():
    early = tiny_run(8, speeds=(0, 1000, 1000, 1000), segment=30)  # one change of speed, at a quarter of the run
    scores = forward_chaining(early, [0])
    assert scores.n_conditions == 2 and not scores.leaves_one_condition
    assert any("only 2 operating conditions" in note for note in trust_notes(scores))
    assert trust_notes(forward_chaining(tiny_run(9), [0])) == ()  # three conditions, six stretches


def test_a_run_that_returns_to_its_two_conditions_is_noted():
    alternating = tiny_run(10, speeds=(2000, 0, 2000, 0, 2000, 0), segment=30)  # six stretches of two conditions
    scores = forward_chaining(alternating, [0])
    assert scores.n_conditions == 2 and scores.n_folds >= 3
    assert any("only 2 operating conditions" in note for note in trust_notes(scores))


@pytest.mark.parametrize(
    "speeds, leaves",
    [
        ((0, 1000), True),  # the second condition starts at half the run, fitted on the first alone
        ((0, 0, 1000, 1000, 1000, 1000), False),  # it starts at a third: the first scored segment repeats it
        ((0, 1000, 0, 1000, 1000), False),  # both seen before 40 %
        ((0, 0, 0, 1000, 2000), True),  # the first scored segment's run before holds 0 r/min alone
    ],
)
def test_a_segment_that_leaves_the_one_condition_before_it_is_noted(speeds, leaves):
    run = tiny_run(8, speeds=speeds, segment=40)
    scores = forward_chaining(run, [0])
    assert scores.leaves_one_condition == leaves
    noted = any("never saw" in note and "--data A B" in note for note in trust_notes(scores))
    assert noted == leaves
    # such a run takes the factor and range learned on warm-up/cool-down runs repeated on another day
    expectation = expect_next_run([run], (0,))
    factor, (low, high) = (
        (calibration.UNSEEN_CONDITION_FACTOR, calibration.UNSEEN_CONDITION_RATIO_RANGE)
        if leaves
        else (calibration.FACTOR, calibration.RATIO_RANGE)
    )
    value, band = expectation.expected()
    assert value == pytest.approx(factor * float(expectation.scores.raw_rms()[0]))
    assert band == pytest.approx((low * value, high * value))
    assert ("warm-up/cool-down" in expectation.method()) == leaves
    assert f"×{factor:.3g}" in expectation.method()


def test_two_runs_left_out_are_noted():
    expectation = expect_next_run([tiny_run(10), tiny_run(11)])
    assert any("only 2 runs to leave out" in note for note in expectation.notes)


def test_a_model_file_with_an_expectation_outside_its_range_is_refused():
    run = tiny_run(12)
    model = GroupedRegressor(p=0).fit(run.temps, run.error).to_model_file(run).to_dict()
    model["training"].update(
        expected_next_run_rms_um=1.0, expected_next_run_range_um=[0.5, 2.0], expected_next_run_method="by hand"
    )
    assert model_problem(model) is None
    model["training"]["expected_next_run_range_um"] = [1.5, 2.0]
    assert "expected_next_run_range_um" in model_problem(model)
    model["training"]["expected_next_run_rms_um"] = -1.0
    assert "expected_next_run_rms_um" in model_problem(model)


@pytest.mark.parametrize(
    "recordings, named",
    [
        ({"path": "a.csv"}, "must hold path, sha256"),
        ("a.csv", "must be a list"),
        ({"path": "a.csv", "sha256": "xyz", "first_time_s": 0, "last_time_s": 1, "period_s": 1}, "64 hex digits"),
        ({"path": "a.csv", "sha256": "0" * 64, "first_time_s": 2, "last_time_s": 1, "period_s": 1}, "first_time_s"),
        ({"path": "a.csv", "sha256": "0" * 64, "first_time_s": 0, "last_time_s": 1, "period_s": 0}, "period_s > 0"),
        ({"path": "", "sha256": "0" * 64, "first_time_s": 0, "last_time_s": 1, "period_s": 1}, "path"),
        (
            {
                "path": "a.csv",
                "sha256": "0" * 64,
                "first_time_s": 0,
                "last_time_s": 1,
                "period_s": 1,
                "path_from_model": 3,
            },
            "path_from_model",
        ),
    ],
)
def test_a_model_file_with_a_bad_recording_entry_is_refused_naming_it(recordings, named):
    run = tiny_run(12)
    model = GroupedRegressor(p=0).fit(run.temps, run.error).to_model_file(run).to_dict()
    good = {"path": "a.csv", "sha256": "0" * 64, "first_time_s": 0.0, "last_time_s": 1.0, "period_s": 1.0}
    model["training"]["recordings"] = [good]
    assert model_problem(model) is None
    model["training"]["recordings"] = recordings if isinstance(recordings, str) else [recordings]
    problem = model_problem(model)
    assert problem is not None and "training.recordings" in problem and named in problem


def test_replay_says_when_a_run_leaves_the_modelling_range(tmp_path, capsys):
    paths = write_runs(tmp_path, (13,))
    out = tmp_path / "fit"
    options = [*FIT_OPTIONS, "--p", "0", "--out", str(out)]
    assert main(["fit", "--data", paths[0], *options]) == 0
    hotter = tiny_frame(14)
    hotter["T1"] += 0.5 * (tiny_frame(13)["T1"].max() - tiny_frame(13)["T1"].min()) + 1.0  # beyond the span
    hotter.to_csv(tmp_path / "hotter.csv", index=False)
    broken = tiny_frame(13)
    broken.loc[40:45, "T1"] = -999.0  # a sensor fault the run-time rule holds, then flags: not the machine's state
    broken.to_csv(tmp_path / "broken.csv", index=False)
    capsys.readouterr()
    runs = ((paths[0], False), (str(tmp_path / "hotter.csv"), True), (str(tmp_path / "broken.csv"), False))
    for data, outside in runs:
        assert main(["replay", str(out / "model.json"), "--data", data, "--json", str(tmp_path / "r.json")]) == 0
        result = json.loads((tmp_path / "r.json").read_text())
        names = [b["input"] for b in result["beyond_modelling_range"]]
        assert names == (["T1"] if outside else [])
        assert ("leaves the modelling range" in capsys.readouterr().out) == outside
    span = ModelFile.load(out / "model.json").training["input_span"]["T1"]
    assert list(span) == [tiny_frame(13)["T1"].min(), tiny_frame(13)["T1"].max()]


def test_diagnose_reports_before_and_after_with_the_estimate_fit_makes(tmp_path, capsys):
    datasets = Path(__file__).resolve().parents[1] / "datasets"
    run = str(datasets / "diag_speed_model.csv")
    out = tmp_path / "fit"
    assert main(["fit", "--data", run, "--temps", "T1,T2", "--p", "0", "--quiet", "--out", str(out)]) == 0
    fitted = ModelFile.load(out / "model.json").training
    capsys.readouterr()
    assert main(["diagnose", str(out / "model.json"), "--data", run, "--out", str(tmp_path / "d"), "--json", "-"]) == 0
    captured = capsys.readouterr()
    expected = json.loads(captured.out)["expected_next_run"]
    # the same structure refitted by the same estimator, reached from the model file instead of fit's run
    assert expected["before"]["expected_next_run_rms_um"] == pytest.approx(fitted["expected_next_run_rms_um"], rel=1e-9)
    augmented = ModelFile.load(tmp_path / "d" / "model_augmented.json").training
    assert augmented["expected_next_run_rms_um"] == expected["after"]["expected_next_run_rms_um"]
    assert "expect  before: about" in captured.err and "expect  after: about" in captured.err


def test_a_thinned_run_pools_the_squared_errors_of_thinnings_from_several_first_rows():
    run = tiny_run(5, segment=60)  # 360 rows: thinned to every third row for at most 120
    scores = forward_chaining(run, [0, 1], n=0, c=1.0, max_samples=120)
    assert scores.stride == 3 and phase_offsets(3) == [0, 1, 2]
    by_hand = []
    for offset in (0, 1, 2):
        frame = tiny_frame(5, segment=60).iloc[offset::3].reset_index(drop=True)
        frame["time_s"] = 180.0 * np.arange(len(frame))
        thin = load_run(frame, name=f"every third from {offset}", temps=["T1", "T2"])
        by_hand.append(forward_chaining(thin, [0, 1], n=0, c=1.0, max_samples=120))
    assert all(h.stride == 1 and h.n_folds == scores.n_folds for h in by_hand)
    np.testing.assert_allclose(scores.sse, sum(h.sse for h in by_hand), rtol=1e-9)
    np.testing.assert_array_equal(scores.counts, sum(h.counts for h in by_hand))
    assert phase_offsets(1) == [0] and phase_offsets(2) == [0, 1] and phase_offsets(12) == [0, 4, 8]


@pytest.mark.parametrize("segment", [5, 8, 20])
def test_the_p_a_short_run_cannot_try_are_named_and_the_choice_says_so(tmp_path, capsys, segment):
    frame = tiny_frame(5, segment=segment)
    run = load_run(frame, name="short", temps=["T1", "T2"])
    # one p at a time, as an independent truth: the estimate refuses a p whose groups do not fit
    fits = []
    for p in (0, 1, 2, 3):
        try:
            expect_next_run([run], (p,))
            fits.append(p)
        except ValueError:
            pass
    expectation = expect_next_run([run], (0, 1, 2, 3))
    assert expectation.candidates == tuple(fits)
    not_tried = tuple(p for p in (0, 1, 2, 3) if p not in fits)
    assert expectation.not_tried == not_tried
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / "m"
    options = [o for o in FIT_OPTIONS if o != "--quiet"]
    assert main(["fit", "--data", str(path), *options, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    choice = json.loads((out / "model.json").read_text())["training"]["model_choice"]
    listed = ", ".join(str(p) for p in not_tried)
    assert choice.get("not_tried", []) == list(not_tried)
    assert (f"p = {listed} not tried" in printed) == bool(not_tried)
    if len(fits) == 1:  # only p = 0 fits the first prefix: said, not shown as a choice among one
        assert f"p       0: p = {listed} not tried" in printed and choice["rule"] == "the only p the run allows"
    assert "raise --pmax" not in printed or not not_tried  # a larger --pmax cannot help a run too short


def test_the_edge_note_names_the_p_a_short_run_did_not_try():
    from groupfit.fitting import choice_summary

    expectation = expect_next_run([tiny_run(5, segment=8)], (0, 1, 2, 3))
    edge = dataclasses.replace(expectation, chosen=expectation.candidates.index(1))
    line = choice_summary(edge)
    assert line.startswith("p       1: ") and "; p = 2, 3 not tried" in line and "--pmax" not in line
    unlimited = dataclasses.replace(edge, not_tried=())
    assert "raise --pmax" in choice_summary(unlimited)
    assert "a longer run or fewer inputs" in line
    # a long run read one sample in k: a longer run is read as sparsely, only fewer inputs shorten the groups
    thinned = dataclasses.replace(edge, scores=dataclasses.replace(edge.scores, stride=5))
    assert "(one sample in 5); fewer inputs (--select) would let" in choice_summary(thinned)
    assert "longer run" not in choice_summary(thinned)


def test_operating_columns_that_never_change_cut_the_run_as_blocks_of_time():
    frame = tiny_frame(11, speeds=(1000,) * 6, segment=30)
    constant = forward_chaining(load_run(frame, name="constant", temps=["T1", "T2"]), [0, 1])
    without = forward_chaining(load_run(frame.drop(columns="speed_rpm"), name="plain", temps=["T1", "T2"]), [0, 1])
    assert constant.blocks_of_time and constant.n_conditions == 1 and "speed_rpm never changing" in constant.segments
    assert "blocks of time" in constant.method() and "changes of" not in constant.method()
    np.testing.assert_allclose(constant.sse, without.sse, rtol=1e-12)
    assert any("one operating condition" in note for note in trust_notes(constant))


def test_fit_expects_a_heat_then_cool_run_with_its_own_calibration(tmp_path):
    path = tmp_path / "warm_cool.csv"
    tiny_frame(15, speeds=(1000, 0), segment=120).to_csv(path, index=False)  # a warm-up, then a cool-down
    result = tmp_path / "fit.json"
    assert main(["fit", "--data", str(path), *FIT_OPTIONS, "--p", "0", "--json", str(result)]) == 0
    data = json.loads(result.read_text())
    scores = forward_chaining(load_run(pd.read_csv(path), name="warm_cool", temps=["T1", "T2"]), [0])
    assert scores.leaves_one_condition
    value = data["expected_next_run_rms_um"]
    assert value == pytest.approx(calibration.UNSEEN_CONDITION_FACTOR * float(scores.raw_rms()[0]), rel=1e-9)
    low, high = calibration.UNSEEN_CONDITION_RATIO_RANGE
    assert data["expected_next_run_range_um"] == pytest.approx([low * value, high * value])
    assert "warm-up/cool-down" in data["expected_next_run_method"]
