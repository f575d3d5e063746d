"""Which check intervals did worse than no checks on held-out data: the tuning's figures and the notes."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from recalibration_cases import KALMAN, with_section
from test_recalibration import ramp_run
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main
from groupfit.model import ModelFile
from groupfit.recalibration_advice import WORSE_BY, interval_advice
from groupfit.recalibration_tuning import candidate_grid, choose_recalibration, held_out_series, replay_candidates

INTERVALS = [900.0, 1800.0, 3600.0, 7200.0]


def chosen(checked, unchecked):
    return {"intervals_s": INTERVALS, "rms_chosen_um": checked, "rms_none_by_interval_um": unchecked}


def test_the_no_check_figure_of_each_interval_is_taken_on_the_samples_the_checked_figures_score():
    model = ModelFile.from_dict(synthetic_model(p=0)[0])  # inputs T1…T4, 100 s per sample
    temps, error = ramp_run(1200, drift=0.02, wander=0.1, seed=3)
    frame = pd.DataFrame(temps, columns=["T1", "T2", "T3", "T4"])
    error[::37] = np.nan  # rows not measured are not scored either way
    tuning = choose_recalibration(model, [(frame, error)], intervals_s=INTERVALS)
    series = held_out_series(model, [(frame, error)])
    candidates = candidate_grid(hold_sigma=1.0, initial_offset=1.0, probe_sigma=0.1)
    for interval, unchecked in zip(INTERVALS, tuning.rms_none_by_interval_um):
        every = int(round(interval / model.sampling_period_s))
        squares, count = 0.0, 0
        for held in series:
            _, scored = replay_candidates(held, candidates, every=every, period_s=model.sampling_period_s)
            after_first_check = [r for k, r in enumerate(held.residual) if k >= every and np.isfinite(r)]
            assert len(after_first_check) == scored
            squares, count = squares + sum(r * r for r in after_first_check), count + scored
        assert unchecked == pytest.approx(np.sqrt(squares / count), rel=1e-12)
    assert tuning.section.chosen["rms_none_by_interval_um"] == list(tuning.rms_none_by_interval_um)


def test_intervals_that_did_worse_than_none_are_named_with_the_longest_that_helped():
    note = interval_advice(chosen([1.0, 1.2, 1.5, 1.9], [1.3, 1.3, 1.3, 1.3]))
    assert "checks every 60/120 min did more than 5 % worse than none" in note
    assert "(1.5/1.9 against 1.3/1.3 µm without checks)" in note and note.endswith("check at least every 30 min")
    everywhere = interval_advice(chosen([1.4, 1.5, 1.6, 1.7], [1.3, 1.3, 1.3, 1.3]))
    assert "15/30/60/120 min" in everywhere and "checks may cost more than they gain" in everywhere
    scattered = interval_advice(chosen([1.0, 1.4, 1.2, 1.2], [1.3, 1.3, 1.3, 1.3]))  # only 30 min: no rule to give
    assert "checks every 30 min" in scattered and "at least every" not in scattered
    assert interval_advice(chosen([1.0, 1.2, 1.3 * (1 + WORSE_BY) * 0.999, 1.3], [1.3] * 4)) is None
    for broken in (None, {}, chosen([1.0, 1.2], [1.3] * 4), chosen(["a"] * 4, [1.3] * 4), {"by": "default"}):
        assert interval_advice(broken) is None


@pytest.mark.parametrize(
    "every_s, noted",
    [(600.0, False), (1800.0, False), (2700.0, False), (3600.0, True), (5000.0, True), (7200.0, True), (9e4, True)],
)
def test_a_replay_is_warned_when_the_nearest_held_out_interval_not_beyond_its_own_did_worse(every_s, noted):
    note = interval_advice(chosen([1.0, 1.2, 1.5, 1.9], [1.3] * 4), every_s)
    assert (note is not None) == noted
    if noted:
        assert note.startswith(f"--probe-every {every_s:g} s: checks every 60/120 min")


def test_replay_and_fit_print_the_note(tmp_path, capsys):
    model, _ = synthetic_model()
    section = {**KALMAN, "chosen": chosen([1.0, 1.2, 1.5, 1.9], [1.3] * 4)}
    path = tmp_path / "model.json"
    ModelFile.from_dict(with_section(model, section)).save(path)
    for every, noted in ((1000, False), (4000, True)):
        out = tmp_path / f"r{every}.json"
        args = ["replay", str(path), "--data", str(SYNTHETIC), "--probe-every", str(every), "--json", str(out)]
        assert main(args) == 0
        notes = [n for n in json.loads(out.read_text()).get("notes", []) if "worse than none" in n]
        assert len(notes) == int(noted)
        assert ("worse than none" in capsys.readouterr().out) == noted
    assert main(["replay", str(path), "--data", str(SYNTHETIC)]) == 0  # no checks: nothing to warn of
    assert "worse than none" not in capsys.readouterr().out
