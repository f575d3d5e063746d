"""The CLI's outputs are those recorded in tests/data/snapshots (``python -m tests.snapshots --update``
rewrites them when a change is meant to alter an output).

Text is compared character for character except decimal numbers, which must agree to
``RTOL`` relative: their last digits follow the LAPACK build that numpy and scipy bring,
which a fresh install does not fix, and a candidate fitted on nearly collinear inputs (a
ridge over lags of one source) carries that rounding up to about 1e-8. A changed break
point, group, chosen effect, report line or key still fails; so does any number that
moves by more than rounding.
"""

import difflib
import math
import re

import pytest
from snapshots import FAST, SCENARIOS, produce, stored

RTOL = 1e-6
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def same_numbers(recorded: str, today: str) -> bool:
    """Equal text around the numbers, and numbers equal to ``RTOL`` relative (``1e-300`` absolute)."""
    if NUMBER.split(recorded) != NUMBER.split(today):
        return False
    pairs = zip(NUMBER.findall(recorded), NUMBER.findall(today), strict=True)
    return all(a == b or math.isclose(float(a), float(b), rel_tol=RTOL, abs_tol=1e-300) for a, b in pairs)


def differs(kept: bytes, data: bytes) -> bool:
    if data == kept:
        return False
    try:
        return not same_numbers(kept.decode(), data.decode())
    except UnicodeDecodeError:
        return True


def assert_same(name: str) -> None:
    produced, kept = produce([name]), stored([name])
    assert kept, f"no snapshot of {name}: run python -m tests.snapshots --update {name}"
    assert sorted(produced) == sorted(kept), "the scenario wrote other files than recorded"
    for key, data in produced.items():
        if differs(kept[key], data):
            diff = difflib.unified_diff(
                kept[key].decode(errors="replace").splitlines(),
                data.decode(errors="replace").splitlines(),
                "recorded",
                "today",
                lineterm="",
                n=1,
            )
            pytest.fail(f"{key} differs from its snapshot:\n" + "\n".join(list(diff)[:40]))


def test_the_comparison_forgives_rounding_and_nothing_else():
    assert not differs(b"c = [-32.31880196053648];", b"c = [-32.31880196053651];")
    assert not differs(b'"score": 0.9781180458259235', b'"score": 0.9781180458259181')
    assert not differs(b'"score": 0.16064585663766995', b'"score": 0.16064585928325215')  # a collinear fit's
    assert differs(b"c = [-32.31880196053648];", b"c = [-32.31890196053648];")
    assert differs(b"break at 1200", b"break at 1201")
    assert differs(b"groups: 3", b"groups: 3 ")
    assert differs(b"x = 1.0", b"x = 1.0, 2.0")
    assert differs(b"\xff1.0", b"\xff1.0000000000001")


@pytest.mark.parametrize("name", FAST)
def test_outputs_equal_their_snapshots(name):
    assert_same(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", [name for name in SCENARIOS if name not in FAST])
def test_outputs_of_the_other_scenarios_equal_their_snapshots(name):
    assert_same(name)
