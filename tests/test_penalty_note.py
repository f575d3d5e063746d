"""The note when the ridge penalty chosen on held-out conditions raises the next-run estimate above least squares'.

``fit`` chooses p by the next-run estimate (forward chaining), then, for a global model, the ridge penalty by
held-out operating conditions. The two checks can disagree; the report says so instead of printing a higher
expectation than the one p was chosen on without a word.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.heldout.expect import penalty_disagreement


@dataclass
class Expected:
    """What the note reads of an expectation: the chosen model's figure and a candidate's."""

    figure: float
    by_p: dict

    def expected(self):
        return self.figure, (0.5 * self.figure, 2.0 * self.figure)

    def for_candidate(self, p):
        return None if p not in self.by_p else (self.by_p[p], (0.0, 0.0))


@pytest.mark.parametrize(
    "penalised, least_squares, says",
    [(5.33, 3.63, True), (3.63, 3.63, False), (3.66, 3.63, False), (2.1, 3.63, False)],
)
def test_the_note_appears_only_when_the_penalty_raises_the_estimate(penalised, least_squares, says):
    note = penalty_disagreement(Expected(penalised, {}), Expected(least_squares, {0: least_squares}), 0.01)
    assert bool(note) == says
    if says:
        assert f"({penalised:.3g} against {least_squares:.3g} µm)" in note and "--ridge 0" in note


def test_no_note_without_a_least_squares_figure_for_p_0():
    assert penalty_disagreement(Expected(5.0, {}), Expected(2.0, {1: 2.0}), 0.01) == ""


@pytest.mark.slow
def test_fit_on_the_measured_test_says_when_its_penalty_raises_the_estimate(measured_data, tmp_path, capsys):
    """The first 40 % of the measured step test: p = 0 is chosen at 3.6 µm expected, the penalty chosen on
    held-out speeds raises the estimate; the note quotes the two figures the report prints."""
    frame = pd.read_csv(measured_data / "fl_thermal" / "spindle_step_test.csv")
    frame.iloc[: int(0.4 * len(frame))].to_csv(tmp_path / "first.csv", index=False)
    args = ["fit", "--data", str(tmp_path / "first.csv"), "--error", "disp_ch3_um", "--recalibrate", "none"]
    assert main([*args, "--quiet", "--out", str(tmp_path / "auto")]) == 0
    report = capsys.readouterr().out
    least = float(re.search(r"expected next-run RMS p=0: ([\d.]+) µm", report).group(1))
    expected = float(re.search(r"expect\s+about ([\d.]+) µm", report).group(1))
    alpha = re.search(r"ridge\s+penalty alpha = ([\d.e-]+)", report).group(1)
    if expected <= 1.01 * least:
        assert "the two checks disagree" not in report
    else:
        assert f"the ridge penalty (alpha {alpha}) was chosen" in report
        assert f"({expected:.3g} against {least:.3g} µm)" in report
    assert main([*args, "--ridge", "0", "--quiet", "--out", str(tmp_path / "plain")]) == 0
    assert "the two checks disagree" not in capsys.readouterr().out
