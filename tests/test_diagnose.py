import json

import numpy as np
import pytest
from support.diagnose_scenarios import TEMPS, fit_model, lumped, sensor_error, with_ambient_effect
from support.grouped_reference import shared_effect_fit

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.augment import augment_model
from groupfit.diagnose.candidates import Candidate, candidate_features, rank_candidates, within_one_se
from groupfit.diagnose.report import column_words
from groupfit.diagnose.residual import model_inputs
from groupfit.fast_response import without_stage
from groupfit.features import Feature, lowpass
from groupfit.heldout.design import group_design
from groupfit.heldout.folds import Folds, make_folds
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.model import ModelFile


def test_held_out_scorer_equals_a_least_squares_refit_on_every_fold():
    rng = np.random.default_rng(0)
    n = 300
    design = np.column_stack([np.ones(n), np.cumsum(rng.normal(size=(n, 3)), axis=0)])
    candidate = np.cumsum(rng.normal(size=n))
    target = design @ [1.0, 0.5, -0.2, 0.3] + 0.8 * candidate + rng.normal(scale=0.5, size=n)
    folds = Folds(np.repeat(np.arange(5), n // 5), "block")
    scorer = HeldOutScorer(target, design, folds)
    augmented = np.column_stack([design, candidate])
    expected_base, expected_with = [], []
    for train, test in folds.splits():
        for matrix, out in ((design, expected_base), (augmented, expected_with)):
            coef = np.linalg.lstsq(matrix[train], target[train], rcond=None)[0]
            out.append(np.sum((target[test] - matrix[test] @ coef) ** 2))
    np.testing.assert_allclose(scorer.base_sse, expected_base, rtol=1e-9)
    np.testing.assert_allclose(scorer.fold_sse(candidate), expected_with, rtol=1e-9)
    assert scorer.fold_sse(rng.normal(size=n)).sum() > scorer.base_sse.sum() * 0.99


def test_held_out_scorer_keeps_its_digits_on_absolute_temperatures():
    """Readings near 25 °C beside a constant make the normal equations lose digits; the scorer's refined
    solution matches scikit-learn's (centred) leave-one-group-out refits to 1e-11, with and without a
    candidate (the plain normal equations miss by 1e-10 to 1e-9 here)."""
    from sklearn.linear_model import LinearRegression
    from sklearn.model_selection import LeaveOneGroupOut, cross_val_predict

    rng = np.random.default_rng(1)
    n = 1200
    common = np.cumsum(rng.normal(scale=0.02, size=n))
    temps = 25.0 + common[:, None] + np.cumsum(rng.normal(scale=0.005, size=(n, 4)), axis=0)
    target = temps @ [3.0, -2.0, 1.5, -2.2] + rng.normal(scale=0.05, size=n)
    candidate = 25.0 + 0.01 * np.cumsum(rng.normal(size=n))
    labels = np.repeat(np.arange(6), n // 6)
    scorer = HeldOutScorer(target, np.column_stack([np.ones(n), temps]), Folds(labels, "block"))

    def fold_sse(design):
        predicted = cross_val_predict(LinearRegression(), design, target, groups=labels, cv=LeaveOneGroupOut())
        return np.array([np.sum((target - predicted)[labels == g] ** 2) for g in range(6)])

    np.testing.assert_allclose(scorer.base_sse, fold_sse(temps), rtol=1e-11)
    np.testing.assert_allclose(scorer.fold_sse(candidate), fold_sse(np.column_stack([temps, candidate])), rtol=1e-11)


def test_ranking_finds_the_generating_transform_even_when_the_inputs_mimic_it():
    frame = lumped()
    X = frame[["T1", "T4"]].to_numpy()
    effect = lowpass(frame["spindle_on"].to_numpy(float), 3600.0, 100.0, before=0.0)
    # T1 follows the same heat: an in-sample fit on T1 absorbs much of the effect
    error = X @ [0.7, 1.3] + 1.5 * effect
    design = np.column_stack([np.ones(len(X)), X])
    features = candidate_features(["spindle_on", "T_amb"], ["T1"], frame, operating=["spindle_on"])
    folds = make_folds([frame], ["spindle_on", "T_amb"])
    assert folds.kind == "condition"

    def compute(feature):
        return feature.compute(frame[feature.column].to_numpy(dtype=float), 100.0)

    ranked = rank_candidates(error, features, compute, HeldOutScorer(error, design, folds), X, own_inputs={"T1"})
    assert ranked[0].feature == Feature("spindle_on", "lowpass", tau_s=3600.0, start="rest")
    assert ranked[0].score == pytest.approx(1.0, abs=1e-9)
    assert ranked[0].coefficient == pytest.approx(1.5, rel=1e-9)
    assert ranked[0].folds_improved == 1.0 and not ranked[0].own_input
    assert all(c.own_input for c in ranked if c.feature.column == "T1")


def test_a_grouped_model_gets_the_effect_with_one_coefficient_as_it_was_scored(tmp_path):
    """One least-squares problem over the hard groups (each its own inputs, the effect shared), then each soft
    group refitted by least squares on what the effect leaves; the shared coefficient is the scorer's."""
    frame = with_ambient_effect(lumped())
    path, model_path = fit_model(tmp_path, frame, "amb", p=2)
    model = without_stage(ModelFile.load(model_path)).to_dict()  # as diagnose takes it
    run = load_run(path, temps=TEMPS)
    feature = Feature("T_amb", "lowpass", tau_s=3600.0)
    augmented = augment_model(model, run, model_inputs(model, run), feature).to_dict()
    assert augmented["temps"] == TEMPS + ["T_amb~lp3600s"] and augmented["breaks"] == model["breaks"]
    effect = feature.compute(frame["T_amb"].to_numpy(), 100.0)
    y = frame["error_um"].to_numpy()
    own = np.column_stack([np.ones(len(frame)), frame[TEMPS]])
    (gamma,), reference, rows = shared_effect_fit(own, effect[:, None], y, model["breaks"], model["n"])
    coefficients = np.asarray(augmented["coefficients"])
    np.testing.assert_allclose(coefficients[:, -1], gamma, rtol=1e-9)
    for row, expected, r in zip(coefficients, reference, rows):
        np.testing.assert_allclose(own[r] @ row[:-1], own[r] @ expected, atol=1e-7)
    scorer = HeldOutScorer(y, group_design(model, model_inputs(model, run)), Folds(np.arange(len(y)) % 2, "block"))
    assert scorer.coefficient(effect) == pytest.approx(gamma, rel=1e-8)


def test_missing_ambient_effect_is_found_and_judged_on_another_run(tmp_path):
    modelling = with_ambient_effect(lumped(seed=0))
    schedule = [[5000.0, 1.0], [3000.0, 0.0], [6000.0, 1.0], [2000.0, 0.0], [30000.0, 1.0]]
    validation = with_ambient_effect(lumped(seed=1, schedule=schedule, ambient_phase_h=7.0))
    data_path, model_path = fit_model(tmp_path, modelling, "modelling")
    validation_path = tmp_path / "validation.csv"
    validation.to_csv(validation_path, index=False)
    model = ModelFile.load(model_path).to_dict()
    result = diagnose(model, load_run(data_path, temps=TEMPS), load_run(validation_path, temps=TEMPS))
    assert [c.feature.column for c in result.added][:1] == ["T_amb"]
    assert result.added[0].feature.transform in ("lowpass", "delay")
    assert result.after["validate"]["rms_um"] <= 0.6 * result.before["validate"]["rms_um"]


def test_nothing_missing_leaves_the_model_unchanged(tmp_path, capsys):
    frame = sensor_error(lumped())
    data_path, model_path = fit_model(tmp_path, frame, "clean")
    out = tmp_path / "diag"
    capsys.readouterr()
    assert main(["diagnose", str(model_path), "--data", str(data_path), "--out", str(out), "--json", "-"]) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert result["added"] == [] and result["model"] == str(model_path)
    assert result["after"] == result["before"] and result["before"]["validate"] is None  # no --validate
    assert result["improved"] is None
    assert "nothing missing" in captured.err
    assert not (out / "model_augmented.json").exists()


def test_when_nothing_is_added_the_first_line_says_why(tmp_path):
    """A refused candidate and an over-fitting base are named at the top, not reported as 'nothing missing'."""
    from dataclasses import replace

    from groupfit.diagnose.notes import OVERFIT, Note
    from groupfit.diagnose.policy import FOLD_WORSENED, Refusal
    from groupfit.diagnose.result import Refused

    frame = sensor_error(lumped())
    data_path, model_path = fit_model(tmp_path, frame, "clean")
    result = diagnose(ModelFile.load(model_path).to_dict(), load_run(data_path, temps=TEMPS))
    assert not result.added and not result.base_check.overfitted
    assert result.summary().splitlines()[0].startswith("nothing missing")
    best = replace(result.candidates[0], score=0.93)
    refusal = Refused(best, Refusal(FOLD_WORSENED, "makes one held-out condition (fold 4) 3.6 times worse (RMS)"))
    check = replace(result.base_check, overfitted=True, held_out_rms_um=18.8, in_sample_rms_um=0.468)
    first, second = replace(result, refused=[refusal], base_check=check).summary().splitlines()[:2]
    assert first == (
        f"no effect added: the best candidate, {column_words(best.feature.column)}, {best.describe()} "
        "(removes 93 % of the held-out mean-square error), was refused: makes one held-out condition (fold 4) "
        "3.6 times worse (RMS)"
    )
    assert second == (
        "the model over-fits (held-out RMS 18.8 µm against 0.468 µm in sample): start from a selected model "
        "(groupfit fit --select forward, or diagnose --select forward)"
    )
    first, second = replace(result, base_check=check).summary().splitlines()[:2]
    assert first == "no effect added: no candidate explains a significant part of the held-out error"
    assert second.startswith("the model over-fits")

    # said once: the note diagnose writes for an over-fitting base is left out where the head says it
    note = Note(OVERFIT, "the model over-fits: held-out RMS 18.8 µm against 0.468 µm in sample; effects found on it")
    report = replace(result, base_check=check, notes=(note, *result.notes)).summary()
    assert report.count("over-fits") == 1 and report.splitlines()[1].startswith("the model over-fits (")
    with_effect = replace(result, base_check=check, notes=(note,), added=result.candidates[:1], steps=())
    assert with_effect.summary().count("over-fits") == 1 and f"note: {note.text}" in with_effect.summary()


def test_measured_data_realities(tmp_path, capsys):
    frame = with_ambient_effect(lumped())
    data_path, model_path = fit_model(tmp_path, frame, "base")
    # a dead unused sensor (NaN) and a stuck one (constant) are left out with a note, noise is tolerated
    noisy = frame.copy()
    noisy["T_dead"] = np.nan
    noisy["T_stuck"] = 25.0
    noisy[TEMPS] += np.random.default_rng(3).normal(scale=0.05, size=(len(noisy), 4))
    noisy_path = tmp_path / "noisy.csv"
    noisy.to_csv(noisy_path, index=False)
    capsys.readouterr()
    assert (
        main(
            [
                "diagnose",
                str(model_path),
                "--data",
                str(noisy_path),
                "--out",
                str(tmp_path / "d1"),
                "--json",
                str(tmp_path / "d1.json"),
            ]
        )
        == 0
    )
    report = capsys.readouterr().out
    result = json.loads((tmp_path / "d1.json").read_text())
    assert result["added"][0]["column"] == "T_amb"
    assert "column 'T_dead' left out" in report and "column 'T_stuck' left out: constant" in report

    # a dead model input and a gap in the samples stop with one clear line
    dead = frame.copy()
    dead.loc[10:20, "T2"] = np.nan
    dead_path = tmp_path / "dead.csv"
    dead.to_csv(dead_path, index=False)
    gap = frame.drop(index=range(100, 110))
    gap_path = tmp_path / "gap.csv"
    gap.to_csv(gap_path, index=False)
    slow = frame.assign(time_s=frame["time_s"] * 2)
    slow_path = tmp_path / "slow.csv"
    slow.to_csv(slow_path, index=False)
    for path, message in [
        (dead_path, "model input 'T2' is not finite at row 11"),
        (gap_path, "sampling is not uniform"),
        (slow_path, "sampled every 200 s but the model every 100 s"),
    ]:
        capsys.readouterr()
        assert main(["diagnose", str(model_path), "--data", str(path), "--out", str(tmp_path / "d2")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0]
        if path == dead_path:
            assert "--resample SECONDS interpolate" in err[0]  # the way out the fit's own refusal names
    # a missed reading or three, interpolated as --resample offers
    short = frame.copy()
    short.loc[10:12, "T2"] = np.nan
    short.to_csv(tmp_path / "short.csv", index=False)
    args = ["diagnose", str(model_path), "--data", str(tmp_path / "short.csv"), "--out", str(tmp_path / "d3")]
    assert main([*args, "--resample", "100"]) == 0


def test_candidates_that_score_alike_keep_the_order_they_were_tried_in():
    def candidate(column, score, fold_sse):
        return Candidate(Feature(column, "lowpass", tau_s=3600.0), score, 1.0, 0.5, fold_sse=fold_sse)

    tried = [candidate("speed_rpm", 0.5217730986920186, (1.0, 2.0, 3.0))]
    tried.append(candidate("spindle_on", 0.5217730986920226, (1.0 + 1e-14, 2.0 - 1e-14, 3.0 + 2e-14)))
    tried.append(candidate("T_amb", 0.5217731, (0.9, 2.0, 3.0)))
    ranked = sorted(tried, key=lambda c: -c.rank)
    assert [c.feature.column for c in ranked] == ["T_amb", "speed_rpm", "spindle_on"]
    assert within_one_se(tried[1], tried[0]) and within_one_se(tried[0], tried[1])
    worse = candidate("T_oil", 0.4, (1.5, 2.6, 3.4))
    assert not within_one_se(worse, tried[0])


def test_a_fold_the_candidate_leaves_as_it_was_but_for_rounding_is_not_counted_as_improved():
    feature = Feature("T_amb", "lowpass", tau_s=3600.0)
    ratios = (1.0 - 4e-16, 0.93, 1.0 + 4e-16, 1.0, 0.999)  # a fit left as it was moves by the last digits alone
    candidate = Candidate(feature, score=0.01, coefficient=1.0, explained_rms_um=0.1, fold_ratios=ratios)
    assert candidate.n_folds_improved == 2 and candidate.folds_improved == pytest.approx(2 / 5)
