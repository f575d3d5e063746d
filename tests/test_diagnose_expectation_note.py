"""diagnose says when its change raises the next-run estimate that fit's estimator gives."""

from __future__ import annotations

import pytest

from groupfit.commands.diagnose import expectation_summary


class _Expectation:
    """The part of a next-run expectation that diagnose's summary reads."""

    notes = ()

    def __init__(self, value):
        self.value = value

    def expected(self):
        return self.value, (0.4 * self.value, 5.2 * self.value)

    def method(self):
        return "forward chaining"


@pytest.mark.parametrize("before, after, rises", [(4.65, 8.19, True), (8.19, 4.65, False), (3.0, 3.0, False)])
def test_a_rising_next_run_estimate_after_a_change_is_said(before, after, rises):
    text = expectation_summary({"before": _Expectation(before), "after": _Expectation(after)})
    assert ("the next-run estimate rises with the change" in text) is rises
    if rises:
        assert f"({before:.3g} → {after:.3g} µm)" in text


def test_no_change_no_note():
    unchanged = _Expectation(4.0)
    assert "rises" not in expectation_summary({"before": unchanged, "after": unchanged})
    assert "rises" not in expectation_summary({"before": None, "after": _Expectation(9.0)})
