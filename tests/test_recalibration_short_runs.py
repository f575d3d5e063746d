"""Tuning the recalibration filter on a modelling run too short for the longest check intervals: the filter is
chosen on the intervals its held-out stretches can score; and the hold a run gets by default (too short to tune
on, or a model file without a section) sizes its gate by the model's expected next-run range."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from test_recalibration import ramp_run
from test_switching_models import synthetic_model

from groupfit.cli import main
from groupfit.model import ModelFile
from groupfit.recalibration_tuning import CUTS, DEFAULT_INITIAL_OFFSET_UM, INTERVALS_S, choose_recalibration
from groupfit.runtime import PROBE_APPLIED, PROBE_CODE_OFFSET, PROBE_REJECTED, SwitchingRule

COLUMNS = ["T1", "T2", "T3", "T4"]


def short_run(n: int, seed: int = 3):
    temps, error = ramp_run(n, drift=0.01, wander=0.1, seed=seed)
    return temps, [(pd.DataFrame(temps, columns=COLUMNS), error)]


def trained(high_um: float) -> ModelFile:
    model = ModelFile.from_dict(synthetic_model(p=0)[0])  # inputs T1…T4, 100 s per sample
    return model.replace(training={**model.training, "expected_next_run_range_um": [1.0, high_um]})


def scored_by_hand(n: int, every: int) -> int:
    """Samples from the first check on, over the held-out stretch of every cut (no row unmeasured)."""
    return sum(max(0, n - int(round(cut * n)) - every) for cut in CUTS)


def test_a_short_run_is_tuned_on_the_intervals_its_held_out_stretches_score_at_least_once_over():
    n = 100  # 2.8 h at 100 s: held out 50 and 30 samples; a check every 1 h (36 samples) scores 14 of them
    model = trained(30.0)
    _, runs = short_run(n)
    everies = [int(round(t / model.sampling_period_s)) for t in INTERVALS_S]
    expected = tuple(t for t, every in zip(INTERVALS_S, everies) if scored_by_hand(n, every) >= every)
    assert expected == (900.0, 1800.0)
    tuning = choose_recalibration(model, runs)
    chosen = tuning.section.chosen
    assert chosen["by"] == "held-out checks" and tuning.intervals_s == expected
    assert chosen["intervals_s"] == list(expected) and chosen["intervals_not_scored_s"] == [3600.0, 7200.0]
    assert len(tuning.rms_hold_um) == len(tuning.rms_chosen_um) == len(expected)
    asked = choose_recalibration(model, runs, intervals_s=expected)  # the same as asking for those alone
    assert asked.rms_hold_um == tuning.rms_hold_um and asked.rms_chosen_um == tuning.rms_chosen_um
    assert dataclasses.replace(tuning.section, chosen=asked.section.chosen) == asked.section
    assert "intervals_not_scored_s" not in asked.section.chosen


@pytest.mark.parametrize("n", [30, 60])
def test_the_default_hold_of_a_run_too_short_to_tune_on_takes_the_offset_the_next_run_range_allows(n):
    # 30 samples: too short to hold part out; 60: held-out stretches shorter than a check every 2 h
    model = trained(30.0)
    temps, runs = short_run(n)
    section = choose_recalibration(model, runs, intervals_s=(7200.0,)).section
    assert section.chosen["by"] == "default" and section.method == "hold"
    assert section.initial_offset_sigma_um == pytest.approx(30.0)
    untrained = choose_recalibration(trained(1.0), runs, intervals_s=(7200.0,)).section
    assert untrained.initial_offset_sigma_um == DEFAULT_INITIAL_OFFSET_UM
    # the next run: another day, 52 µm off (beyond five priors of 10 µm, within five of 30 µm), checked at the
    # third sample and every 10 after
    plain = SwitchingRule(model).replay(temps).prediction_um
    next_error = plain + 52.0
    probes = np.full(n, np.nan)
    rows = np.arange(2, n, 10)
    probes[rows] = next_error[rows]
    codes = {}
    for label, recal in (("range", section), ("default", untrained)):
        replay = SwitchingRule(model.replace(recalibration=recal)).replay(temps, probes)
        codes[label] = [int(replay.probe[i]) - PROBE_CODE_OFFSET for i in rows]
    assert codes["range"] == [PROBE_APPLIED] * len(rows)
    assert codes["default"][0] == PROBE_REJECTED


def test_fit_on_a_short_run_says_which_check_intervals_it_could_not_score(tmp_path, capsys):
    temps, runs = short_run(100)
    frame, error = runs[0]
    path = tmp_path / "short.csv"
    frame.assign(time_s=100.0 * np.arange(len(frame)), error_um=error).to_csv(path, index=False)
    assert main(["fit", "--data", str(path), "--p", "0", "--out", str(tmp_path / "fit")]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("recal"))
    chosen = ModelFile.load(tmp_path / "fit" / "model.json").recalibration.chosen
    assert list(chosen["intervals_s"]) == [900.0, 1800.0] and list(chosen["intervals_not_scored_s"]) == [3600.0, 7200.0]
    assert "a check every 15/30 min" in line and line.endswith("every 60/120 min not scored: the run is too short")


@pytest.mark.parametrize("high_um, first", [(30.0, PROBE_APPLIED), (5.0, PROBE_REJECTED), (None, PROBE_REJECTED)])
def test_a_model_without_a_section_replays_checks_through_the_hold_gated_by_its_next_run_range(high_um, first):
    model = trained(high_um if high_um is not None else 1.0)
    if high_um is None:  # an older model file: no expected next-run range
        model = model.replace(training={k: v for k, v in model.training.items() if "expected" not in k})
    model = model.replace(recalibration=None)
    temps, _ = short_run(60)
    plain = SwitchingRule(model).replay(temps).prediction_um
    probes = np.full(len(temps), np.nan)
    probes[2] = plain[2] + 52.0  # beyond five priors of 10 µm, within five of 30 µm
    table = SwitchingRule(model).tables.recalibration
    assert table.method == "hold" and table.p0[0] == pytest.approx(max(10.0, high_um or 0.0) ** 2)
    replay = SwitchingRule(model).replay(temps, probes)
    assert int(replay.probe[2]) - PROBE_CODE_OFFSET == first
