"""Recalibration from probe checks: the section's validation, the filter against a textbook Kalman filter,
the hold's closed form, the gate, faults, bounds, and the held-out tuning."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from recalibration_cases import HOLD, KALMAN, QUIET, probe_schedule, with_section
from test_switching_models import fault_injected, synthetic_model

from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.recalibration_tuning import (
    CUTS,
    INDIFFERENCE,
    HeldOut,
    _most_responsive_of_the_best,
    candidate_grid,
    choose_recalibration,
    held_out_series,
    replay_candidates,
    score_candidates,
    white_sigma,
)
from groupfit.runtime import (
    PROBE_APPLIED,
    PROBE_CODE_OFFSET,
    PROBE_IGNORED,
    PROBE_REJECTED,
    RuleTables,
    SwitchingRule,
)
from groupfit.runtime.recalibration import Recalibrator, RecalTable


def model_with(section: dict) -> dict:
    model, _ = synthetic_model()
    return with_section(model, section)


# ----------------------------------------------------------------- the section


@pytest.mark.parametrize(
    "change, named",
    [
        ({"method": "median"}, "recalibration.method"),
        ({"terms": ["drift", "offset"]}, "recalibration.terms"),
        ({"terms": ["offset", "gain", "drift"]}, "recalibration.terms"),
        ({"terms": ["offset", "offset"]}, "recalibration.terms"),
        ({"gate_sigmas": 0.0}, "recalibration.gate_sigmas"),
        ({"offset_sigma_um_per_sqrt_h": -1.0}, "recalibration.offset_sigma_um_per_sqrt_h"),
        ({"probe_sigma_um": float("nan")}, "recalibration.probe_sigma_um"),
        ({"offset_max_um": 1e9}, "recalibration.offset_max_um"),
        ({"drift_tau_h": 0}, "recalibration.drift_tau_h"),
        ({"confirm_after": 1.5}, "recalibration.confirm_after"),
        ({"confirm_after": True}, "recalibration.confirm_after"),
        ({"gain_max": 0.0}, "recalibration.gain_max"),
        ({"terms": ["offset", "drift"]}, "'gain' is not among the terms"),
        ({"chosen": [1, 2]}, "recalibration.chosen"),
        ({"rate_um_per_sample": None}, "recalibration.rate_um_per_sample"),
    ],
)
def test_a_bad_kalman_section_is_refused_naming_its_key(change, named):
    with pytest.raises(InputError, match=named.replace(".", r"\.").replace("(", r"\(")):
        ModelFile.from_dict(model_with({**KALMAN, **change}))


@pytest.mark.parametrize(
    "change, named",
    [
        ({"terms": ["offset", "drift"]}, "the hold carries the offset only"),
        ({"probe_sigma_um": 0.5}, "probe_sigma_um must be 0 for the hold"),
        ({"initial_gain_sigma": 0.5}, "'gain' is not among the terms"),
    ],
)
def test_a_hold_with_filter_terms_is_refused(change, named):
    with pytest.raises(InputError, match=named):
        ModelFile.from_dict(model_with({**HOLD, **change}))


def test_a_section_lacking_a_key_is_refused_and_the_section_round_trips(tmp_path):
    section = {key: value for key, value in HOLD.items() if key != "gate_sigmas"}
    with pytest.raises(InputError, match="recalibration lacks key 'gate_sigmas'"):
        ModelFile.from_dict(model_with(section))
    data = model_with({**KALMAN, "chosen": {"by": "hand", "intervals_s": [900.0, 1800.0]}})
    model = ModelFile.from_dict(data)
    model.save(tmp_path / "m.json")
    again = ModelFile.load(tmp_path / "m.json")
    assert again.to_dict()["recalibration"] == data["recalibration"]
    assert again.recalibration.terms == ("offset", "drift", "gain")


# ----------------------------------------------------------------- the filter


def textbook_kalman(residual, prediction, checks, table: RecalTable):
    """Offset/drift/gain Kalman filter in matrix form (numpy), no gate, no bounds: the correction per sample."""
    F = np.array([[1.0, 1.0, 0.0], [0.0, table.phi, 0.0], [0.0, 0.0, 1.0]])
    Q = np.diag(table.q)
    x = np.zeros(3)
    P = np.diag(table.p0)
    out = np.empty(len(residual))
    for k in range(len(residual)):
        x = F @ x
        P = F @ P @ F.T + Q
        H = np.array([1.0, 0.0, prediction[k]])
        out[k] = H @ x
        if checks[k]:
            S = H @ P @ H + table.r
            K = P @ H / S
            x = x + K * (residual[k] - H @ x)
            P = (np.eye(3) - np.outer(K, H)) @ P
    return out


def test_the_filter_is_the_textbook_kalman_filter_when_no_bound_or_gate_acts():
    section = {**KALMAN, "gate_sigmas": 1e5, "offset_max_um": 1e5, "drift_max_um_per_h": 1e5, "gain_max": 1e3}
    section["significance_sigmas"] = 0.0
    section["rate_um_per_sample"] = 1e5
    model = ModelFile.from_dict(model_with(section))
    table = RuleTables.from_model(model).recalibration
    rng = np.random.default_rng(4)
    n = 300
    prediction = 5.0 + np.cumsum(rng.normal(0, 0.3, n))
    residual = 0.8 + 0.01 * np.arange(n) + 0.1 * prediction + rng.normal(0, 0.2, n)
    checks = np.zeros(n, dtype=bool)
    checks[9::10] = True
    expected = textbook_kalman(residual, prediction, checks, table)
    recal = Recalibrator(table)
    got = np.empty(n)
    for k in range(n):
        recal.propagate()
        got[k] = recal.correct(prediction[k])
        if checks[k]:
            assert recal.probe(prediction[k] + residual[k]) == PROBE_APPLIED
    assert np.max(np.abs(got - expected)) <= 1e-9 * (1 + np.max(np.abs(expected)))
    assert np.max(np.abs(got)) > 1.0  # the filter did move


def replay_run(model, temps, probes, precision="double"):
    rule = SwitchingRule(model, precision=precision)
    return rule.replay(temps, probes)


def test_the_hold_makes_the_next_prediction_miss_by_the_change_since_the_check():
    model, run = synthetic_model()
    model = with_section(model, {**HOLD, "gate_sigmas": 1e5, "rate_um_per_sample": 1e5})
    error = run.error + 2.0 + 0.01 * np.arange(run.n_samples)  # a day with an offset and a drift
    probes = np.full(run.n_samples, np.nan)
    probes[49::50] = error[49::50]
    plain = replay_run(model, run.temps, None)
    checked = replay_run(model, run.temps, probes)
    applied = np.flatnonzero(~np.isnan(probes))
    for check, following in zip(applied, list(applied[1:]) + [run.n_samples]):
        held = error[check] - plain.prediction_um[check]  # the residual at the check becomes the offset
        np.testing.assert_allclose(
            checked.prediction_um[check + 1 : following], plain.prediction_um[check + 1 : following] + held, atol=1e-9
        )
    assert checked.probe_counts() == {"applied": len(applied), "rejected": 0, "ignored": 0}


def test_a_gross_reading_is_rejected_and_changes_nothing():
    model, run = synthetic_model()
    model = with_section(model, KALMAN)
    clean = probe_schedule(run.error, 20)
    gross = probe_schedule(run.error, 20, gross_at=4)
    skipped = clean.copy()
    skipped[np.flatnonzero(~np.isnan(clean))[4]] = np.nan  # the same schedule without that check
    with_gross = replay_run(model, run.temps, gross)
    without = replay_run(model, run.temps, skipped)
    assert with_gross.probe_counts()["rejected"] == 1
    assert with_gross.prediction_um.tobytes() == without.prediction_um.tobytes()


def test_checks_that_keep_disagreeing_are_applied_after_confirm_after_rejections():
    model, run = synthetic_model()
    model = ModelFile.from_dict(with_section(model, {**KALMAN, "confirm_after": 2}))
    rule = SwitchingRule(model)
    codes = []
    for k, row in enumerate(run.temps[:60]):
        rule.step(row)
        if k in (10, 20, 30, 40):
            codes.append(rule.probe(run.error[k] + 25.0))  # the machine moved by 25 µm: a real change
    assert codes == [PROBE_REJECTED, PROBE_REJECTED, PROBE_APPLIED, PROBE_APPLIED]


def test_a_check_right_after_a_switch_is_gated_with_the_switch_s_gap_and_the_same_miss_elsewhere_is_not():
    """The innovation a switch causes itself (its gap) passes the gate; the same miss away from a switch is gross."""
    model, run = synthetic_model()
    model = ModelFile.from_dict(with_section(model, {**QUIET, "confirm_after": 1}))
    plain = SwitchingRule(model).replay(run.temps, np.full(run.n_samples, np.nan))
    first = int(np.flatnonzero(plain.switched)[0])
    blend = model.switching.blend_samples
    # the replay's output at the switch is the new group's plus blend / (blend + 1) of the gap: solve for the gap
    gap = (blend + 1) * (plain.prediction_um[first - 1] - plain.prediction_um[first])
    table = RuleTables.from_model(model).recalibration
    gate_without_switch = table.gate2 * (table.p0[0] + first * table.q[0] + table.r)
    assert gap * gap > gate_without_switch  # the old gate would take the switch's own gap for a gross reading

    def code_of_a_check_at(k: int, miss: float) -> int:
        rule = SwitchingRule(model)
        for row in run.temps[: k + 1]:
            rule.step(row)
        return rule.probe(plain.prediction_um[k] + miss)

    assert code_of_a_check_at(first, gap) == PROBE_APPLIED
    assert code_of_a_check_at(first - 5, gap) == PROBE_REJECTED
    assert code_of_a_check_at(first, 3.0 * abs(gap) + 10.0) == PROBE_REJECTED  # beyond the gap still gross


def test_the_gate_is_never_narrower_than_a_new_run_s_offset_so_a_real_step_is_taken_and_a_gross_one_is_not():
    """With a quiet filter locked on, a 12 µm step passes when a new run may be 5 µm off (gate 4·5 µm)."""
    model, run = synthetic_model()
    quiet = {**QUIET, "confirm_after": 2}

    def codes(initial_offset_sigma_um: float, step_um: float) -> list[int]:
        rule = SwitchingRule(
            ModelFile.from_dict(with_section(model, {**quiet, "initial_offset_sigma_um": initial_offset_sigma_um}))
        )
        plain = SwitchingRule(model).replay(run.temps, np.full(run.n_samples, np.nan)).prediction_um
        out = []
        for k, row in enumerate(run.temps[:61]):
            rule.step(row)
            if k % 10 == 0 and k:
                out.append(rule.probe(plain[k] + (step_um if k >= 40 else 0.0)))
        return out

    assert (4.0 * 5.0) ** 2 > 12.0**2 > 4.0**2 * (0.05**2 + KALMAN["probe_sigma_um"] ** 2)  # floor passes, S alone not
    assert codes(5.0, 12.0) == [PROBE_APPLIED] * 6
    assert codes(0.05, 12.0) == [PROBE_APPLIED] * 3 + [PROBE_REJECTED, PROBE_REJECTED, PROBE_APPLIED]
    assert codes(5.0, 500.0) == [PROBE_APPLIED] * 3 + [PROBE_REJECTED, PROBE_REJECTED, PROBE_APPLIED]


def test_a_check_during_a_sensor_fault_or_on_held_readings_is_ignored_and_changes_nothing():
    model, run = synthetic_model()
    section = model["switching"]
    model = with_section(model, KALMAN)
    temps = fault_injected(run.temps, section["hold_samples"], section["criterion_index"], seed=2)
    plain = replay_run(model, temps, None)
    faulty = np.flatnonzero(plain.fault != 0)
    assert faulty.size and np.any(plain.fault & 2) and np.any(plain.fault == 1)
    probes = np.full(run.n_samples, np.nan)
    probes[faulty] = run.error[faulty]
    checked = replay_run(model, temps, probes)
    assert checked.probe_counts() == {"applied": 0, "rejected": 0, "ignored": faulty.size}
    assert checked.prediction_um.tobytes() == plain.prediction_um.tobytes()
    for value in (np.inf, -np.inf, 2e5):  # not a reading
        rule = SwitchingRule(model)
        rule.step(run.temps[0])
        assert rule.probe(value) == PROBE_IGNORED
    assert SwitchingRule(model).probe(1.0) == PROBE_IGNORED  # before the first sample


def test_the_correction_is_bounded_and_rate_limited():
    model, run = synthetic_model()
    section = {**HOLD, "offset_max_um": 3.0, "rate_um_per_sample": 0.25, "gate_sigmas": 1e5}
    model = with_section(model, section)
    probes = np.full(run.n_samples, np.nan)
    probes[29::30] = run.error[29::30] + 10.0  # 10 µm off: the bound holds the offset at 3 µm
    plain = replay_run(model, run.temps, None)
    checked = replay_run(model, run.temps, probes)
    correction = checked.prediction_um - plain.prediction_um
    assert np.max(np.abs(correction)) <= 3.0 + 1e-12
    assert np.max(np.abs(np.diff(correction))) <= 0.25 + 1e-12
    assert correction[-1] == pytest.approx(3.0)


def test_a_correction_is_applied_only_once_the_average_of_the_checks_stands_out_of_its_noise():
    """Offset alone, no wander: the estimate after n checks is their shrunk mean with variance r/(n + r/p0)."""
    section = {**KALMAN, "terms": ["offset"], "offset_sigma_um_per_sqrt_h": 1e-9}
    section.update(drift_sigma_um_per_h_per_sqrt_h=0.0, initial_drift_sigma_um_per_h=0.0)
    section.update(gain_sigma_per_sqrt_h=0.0, initial_gain_sigma=0.0, gain_max=0.0)
    section.update(gate_sigmas=1e5, rate_um_per_sample=1e5, significance_sigmas=2.0, drift_max_um_per_h=0.0)
    model = ModelFile.from_dict(model_with(section))
    table = RuleTables.from_model(model).recalibration
    r, p0 = table.r, table.p0[0]
    rng = np.random.default_rng(3)
    checks = 0.12 + rng.normal(0.0, math.sqrt(r), 40)  # a small offset under noise of 0.2 µm
    recal = Recalibrator(table)
    outcomes = set()
    for n, z in enumerate(checks, start=1):
        recal.propagate()
        recal.correct(0.0)
        recal.probe(z)
        recal.propagate()
        applied = recal.correct(0.0)
        estimate = float(np.sum(checks[:n])) / (n + r / p0)
        deviation2 = r / (n + r / p0)
        stands_out = estimate**2 > 4.0 * deviation2
        assert applied == pytest.approx(estimate if stands_out else 0.0, abs=1e-6)
        outcomes.add(stands_out)
    assert outcomes == {True, False}  # both sides of the test were met


def test_the_noise_of_a_check_is_the_white_part_of_the_held_out_residual():
    rng = np.random.default_rng(11)
    n = 4000
    slow = 3.0 * np.sin(np.arange(n) / 300.0)
    for sigma in (0.05, 0.3):
        residual = slow + rng.normal(0.0, sigma, n)
        residual[::97] = np.nan  # samples not measured
        assert white_sigma([HeldOut(residual, np.zeros(n))]) == pytest.approx(sigma, rel=0.06)
        sparse = np.full(n, np.nan)
        sparse[::5] = residual[::5]  # the error measured on one row in five: steps span five samples
        expected = math.sqrt(sigma**2 + 0.5 * np.mean(np.diff(slow[::5]) ** 2))
        assert white_sigma([HeldOut(sparse, np.zeros(n))]) == pytest.approx(expected, rel=0.1)


# ----------------------------------------------------------------- the tuning


def test_the_vectorised_replay_of_the_tuning_is_the_run_time_filter():
    rng = np.random.default_rng(7)
    n, period = 400, 60.0
    prediction = 3.0 + np.cumsum(rng.normal(0, 0.2, n))
    residual = np.cumsum(rng.normal(0, 0.15, n)) + 0.05 * prediction
    held = HeldOut(residual, prediction)
    candidates = candidate_grid(hold_sigma=2.0, initial_offset=2.0, probe_sigma=0.3)
    assert {bool(v) for v in candidates.significance_sigmas[1:] > 0} == {True}
    picks = [0, 1, 50, len(candidates) - 1]
    totals, scored = replay_candidates(held, candidates, every=15, period_s=period)
    assert scored == n - 15  # from the first check on
    for k in picks:
        section = candidates.section(k, offset_max_um=1e5, rate_um=1e5, chosen={})
        recal = Recalibrator(RecalTable.from_section(section, period))
        error = np.empty(n)
        for i in range(n):
            recal.propagate()
            correction = recal.correct(prediction[i])
            error[i] = residual[i] - correction if i >= 15 else 0.0
            if (i + 1) % 15 == 0:
                recal.probe(prediction[i] + residual[i])
        assert totals[k] == pytest.approx(float(np.sum(error**2)), rel=1e-9)


def ramp_run(n: int, *, drift: float, wander: float, seed: int):
    """Four sensors and an error that is a linear model of them plus a drift per sample and a random walk."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    temps = np.column_stack([20 + 4 * np.sin(k / (30.0 + 9 * j)) + rng.normal(0, 0.02, n) for j in range(4)])
    error = temps @ np.array([2.0, -1.0, 0.5, 1.0]) + drift * k + np.cumsum(rng.normal(0, wander, n))
    return temps, error


def test_tuning_keeps_the_hold_on_a_random_walk_and_takes_a_drift_when_the_error_drifts():
    import pandas as pd

    model = ModelFile.from_dict(synthetic_model(p=0)[0])  # inputs T1…T4, 100 s per sample
    ratios, sections = {}, {}
    for label, drift, wander in (("walk", 0.0, 0.3), ("drift", 0.05, 0.01)):
        temps, error = ramp_run(1200, drift=drift, wander=wander, seed=5)
        frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"])
        tuning = choose_recalibration(model, [(frame, error)], intervals_s=(1000.0, 2000.0, 4000.0))
        ratio = [c / h for c, h in zip(tuning.rms_chosen_um, tuning.rms_hold_um)]
        # never worse than the hold beyond the tolerance, and far better than no checks
        assert max(ratio) <= 1.02 and max(tuning.rms_chosen_um) < 0.5 * tuning.rms_none_um
        ratios[label], sections[label] = ratio, tuning.section
    assert min(ratios["walk"]) > 0.9  # nothing beats holding a random walk by much
    assert sections["drift"].method == "kalman" and "drift" in sections["drift"].terms
    assert max(ratios["drift"]) < 0.7 and np.mean(ratios["drift"]) < 0.5  # a drift is extrapolated between checks
    assert math.isfinite(sections["drift"].chosen["rms_none_um"])


def test_the_scored_table_is_the_one_behind_the_choice_and_the_choice_is_within_the_band_of_its_best():
    import pandas as pd

    model = ModelFile.from_dict(synthetic_model(p=0)[0])
    temps, error = ramp_run(1200, drift=0.05, wander=0.01, seed=5)
    runs = [(pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"]), error)]
    intervals = (1000.0, 2000.0, 4000.0)
    scores = score_candidates(model, runs, intervals_s=intervals)
    tuning = choose_recalibration(model, runs, intervals_s=intervals)
    assert scores.reason == "" and scores.intervals_s == tuning.intervals_s
    assert scores.rms_um.shape == (len(intervals), len(scores.candidates))
    np.testing.assert_array_equal(scores.rms_um[:, 0], tuning.rms_hold_um)
    np.testing.assert_array_equal(scores.rms_um[:, scores.chosen], tuning.rms_chosen_um)
    kept = scores.candidates.section(scores.chosen, offset_max_um=1.0, rate_um=1.0, chosen={})
    assert kept.terms == tuning.section.terms
    assert kept.offset_sigma_um_per_sqrt_h == tuning.section.offset_sigma_um_per_sqrt_h
    score = np.mean(np.log(scores.rms_um / scores.rms_um[:, :1]), axis=0)
    assert score[scores.chosen] <= score.min() + INDIFFERENCE
    assert scores.chosen != int(np.argmin(score))  # here the band keeps a simpler or more responsive filter
    short = score_candidates(model, [(runs[0][0].iloc[:30], error[:30])], intervals_s=intervals)
    assert short.reason and short.candidates is None  # too short to hold part out: said, nothing scored


def test_the_no_check_figure_of_each_interval_is_taken_on_the_samples_the_checked_figures_score():
    import pandas as pd

    model = ModelFile.from_dict(synthetic_model(p=0)[0])  # inputs T1…T4, 100 s per sample
    temps, error = ramp_run(1200, drift=0.02, wander=0.1, seed=3)
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"])
    error[::37] = np.nan  # rows not measured are not scored either way
    intervals = (900.0, 1800.0, 3600.0, 7200.0)
    tuning = choose_recalibration(model, [(frame, error)], intervals_s=intervals)
    series = held_out_series(model, [(frame, error)])
    candidates = candidate_grid(hold_sigma=1.0, initial_offset=1.0, probe_sigma=0.1)
    for interval, unchecked in zip(intervals, tuning.rms_none_by_interval_um):
        every = int(round(interval / model.sampling_period_s))
        squares, count = 0.0, 0
        for held in series:
            _, scored = replay_candidates(held, candidates, every=every, period_s=model.sampling_period_s)
            after_first_check = [r for k, r in enumerate(held.residual) if k >= every and np.isfinite(r)]
            assert len(after_first_check) == scored
            squares, count = squares + sum(r * r for r in after_first_check), count + scored
        assert unchecked == pytest.approx(math.sqrt(squares / count), rel=1e-12)
    assert tuning.section.chosen["rms_none_by_interval_um"] == list(tuning.rms_none_by_interval_um)
    assert len(set(tuning.rms_none_by_interval_um)) == len(intervals)  # each on its own samples


def test_tuning_on_error_rows_measured_in_short_probe_cycles_takes_no_statistic_of_nothing():
    import pandas as pd

    model = ModelFile.from_dict(synthetic_model(p=0)[0])  # inputs T1…T4, 100 s per sample
    temps, error = ramp_run(1200, drift=0.0, wander=0.3, seed=5)
    error[np.arange(len(error)) % 60 >= 12] = np.nan  # 12 measured rows in every 60
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no mean or maximum of an empty or all-NaN slice
        tuning = choose_recalibration(model, [(frame, error)], intervals_s=(1000.0, 2000.0, 4000.0))
    # checks 20 and 40 samples apart never meet two measured rows; the RMS without checks is over measured rows
    held_out = []
    design = np.column_stack([np.ones(len(temps)), temps])
    for cut in CUTS:
        a = int(round(cut * len(temps)))
        train = np.isfinite(error[:a])
        coef = np.linalg.lstsq(design[:a][train], error[:a][train], rcond=None)[0]
        held_out.append(error[a:] - design[a:] @ coef)
    residual = np.concatenate(held_out)
    assert tuning.rms_none_um == pytest.approx(math.sqrt(np.mean(residual[np.isfinite(residual)] ** 2)), rel=1e-9)


def test_the_first_check_of_a_new_day_is_taken_up_when_the_next_run_range_allows_its_offset():
    import pandas as pd

    model = ModelFile.from_dict(synthetic_model(p=0)[0])  # inputs T1…T4, 100 s per sample
    temps, error = ramp_run(1200, drift=0.0, wander=0.02, seed=3)  # a quiet modelling run: checks change little
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"])
    trained = model.replace(training={**model.training, "expected_next_run_range_um": [1.0, 30.0]})
    assert choose_recalibration(trained, [(frame, error)]).section.initial_offset_sigma_um == pytest.approx(30.0)
    untrained = choose_recalibration(model, [(frame, error)], method="hold").section
    wide = choose_recalibration(trained, [(frame, error)], method="hold").section
    assert untrained.initial_offset_sigma_um < 5.0 and wide.initial_offset_sigma_um == pytest.approx(30.0)
    # the next run: another day, 20 µm off from its start; a check every 40 samples, a gross one at the sixth
    plain = SwitchingRule(model).replay(temps).prediction_um
    next_error = plain + 20.0
    probes = np.full(len(temps), np.nan)
    rows = np.arange(39, len(temps), 40)
    probes[rows] = next_error[rows]
    probes[rows[5]] += 500.0
    results = {}
    for label, section in (("untrained", untrained), ("wide", wide)):
        replay = SwitchingRule(model.replace(recalibration=section)).replay(temps, probes)
        codes = [int(replay.probe[i]) - PROBE_CODE_OFFSET for i in rows]
        rms = math.sqrt(np.mean((next_error - replay.prediction_um)[40:] ** 2))
        results[label] = codes, rms
    codes, rms = results["wide"]
    assert codes[0] == PROBE_APPLIED and codes[5] == PROBE_REJECTED and codes.count(PROBE_REJECTED) == 1
    assert rms < 0.1 * 20.0
    codes, rms = results["untrained"]  # the in-run scatter alone takes the new day for a gross reading
    assert codes[:2] == [PROBE_REJECTED, PROBE_REJECTED] and rms > 2 * results["wide"][1]


def test_the_data_not_telling_filters_apart_the_simplest_kalman_filter_is_kept_then_the_most_responsive():
    candidates = candidate_grid(hold_sigma=2.0, initial_offset=2.0, probe_sigma=0.3)
    terms = [tuple(t) for t in candidates.terms]

    def index(wanted_terms, offset):
        return next(
            k for k in range(1, len(candidates)) if terms[k] == wanted_terms and candidates.offset_sigma[k] == offset
        )

    plain, gained = index(("offset",), 0.3), index(("offset", "gain"), 10.0)
    drifting = index(("offset", "drift"), 3.0)
    score = np.full(len(candidates), 1.0)
    score[[0, plain, gained, drifting]] = [0.0, 0.01, 0.005, 0.015]  # the hold best; all four within the band
    assert _most_responsive_of_the_best(candidates, score, kalman=False) == plain
    score[plain] = 1.0  # only filters with two terms left beside the hold: the most responsive of them
    assert _most_responsive_of_the_best(candidates, score, kalman=False) == gained
    score[[gained, drifting]] = 1.0  # the hold alone in the band
    assert _most_responsive_of_the_best(candidates, score, kalman=False) == 0
    assert _most_responsive_of_the_best(candidates, score, kalman=True) != 0


def test_an_applied_check_widens_the_models_clamp_to_twice_the_measured_error_within_the_output():
    section = {**KALMAN, "gate_sigmas": 1e5, "significance_sigmas": 0.0}
    table = RuleTables.from_model(ModelFile.from_dict(model_with(section))).recalibration
    recal = Recalibrator(table, clamp=(-10.0, 10.0), output=(-30.0, 30.0))
    expected = [(4.0, (-10.0, 10.0)), (7.0, (-14.0, 14.0)), (-9.0, (-18.0, 18.0)), (6.0, (-18.0, 18.0))]
    expected += [(-40.0, (-30.0, 30.0))]
    for z, bounds in expected:
        recal.propagate()
        recal.correct(0.0)
        assert recal.probe(z) == PROBE_APPLIED
        assert (recal.clamp_low, recal.clamp_high) == bounds
    recal.propagate()
    recal.correct(0.0)
    recal.invalidate()
    assert recal.probe(100.0) == PROBE_IGNORED  # a check not taken widens nothing
    assert (recal.clamp_low, recal.clamp_high) == (-30.0, 30.0)
    recal.reset()
    assert (recal.clamp_low, recal.clamp_high) == (-10.0, 10.0)


def test_the_check_that_widens_the_clamp_keeps_the_error_where_it_measured_it():
    # the model predicts -14 µm, held at its clamp of 10; the check measures -9: it over-predicts
    table = RuleTables.from_model(ModelFile.from_dict(model_with(HOLD))).recalibration
    recal = Recalibrator(table, clamp=(-10.0, 10.0), output=(-30.0, 30.0))
    recal.propagate()
    recal.correct(-10.0, command_um=-14.0)
    assert recal.probe(-9.0) == PROBE_APPLIED
    assert (recal.clamp_low, recal.clamp_high) == (-18.0, 18.0)  # 2·|z|: the model's -14 is no longer held
    # the hold takes the check's residual against the model's command under the widened clamp: -9 - (-14)
    assert recal.model_um == -14.0 and recal.x[0] == pytest.approx(5.0, abs=1e-12)
    for _ in range(20):  # the applied correction moves at its rate
        recal.propagate()
        served = -14.0 + recal.correct(-14.0, command_um=-14.0)
    assert served == pytest.approx(-9.0, abs=1e-12)
    # without a clamp to widen nothing moves: the residual against the command it checked
    recal = Recalibrator(table, clamp=(-10.0, 10.0), output=(-30.0, 30.0))
    recal.propagate()
    recal.correct(-6.0, command_um=-6.0)
    assert recal.probe(-9.0) == PROBE_APPLIED and recal.x[0] == pytest.approx(-3.0, abs=1e-12)
