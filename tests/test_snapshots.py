"""The CLI's outputs are byte for byte those recorded in tests/data/snapshots (``python -m tests.snapshots --update``
rewrites them when a change is meant to alter an output)."""

import difflib

import pytest
from snapshots import FAST, SCENARIOS, produce, stored


def assert_same(name: str) -> None:
    produced, kept = produce([name]), stored([name])
    assert kept, f"no snapshot of {name}: run python -m tests.snapshots --update {name}"
    assert sorted(produced) == sorted(kept), "the scenario wrote other files than recorded"
    for key, data in produced.items():
        if data != kept[key]:
            diff = difflib.unified_diff(
                kept[key].decode(errors="replace").splitlines(),
                data.decode(errors="replace").splitlines(),
                "recorded",
                "today",
                lineterm="",
                n=1,
            )
            pytest.fail(f"{key} differs from its snapshot:\n" + "\n".join(list(diff)[:40]))


@pytest.mark.parametrize("name", FAST)
def test_outputs_equal_their_snapshots(name):
    assert_same(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", [name for name in SCENARIOS if name not in FAST])
def test_outputs_of_the_other_scenarios_equal_their_snapshots(name):
    assert_same(name)
