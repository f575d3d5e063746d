"""A stage without progress of its own says it is still running, so a long log is never silent for minutes."""

import io
import re
import time

import pytest

from groupfit.commands import running


def lines_of(stream: io.StringIO) -> list[str]:
    return stream.getvalue().splitlines()


def test_a_long_stage_says_it_runs_and_when_it_is_done():
    stream = io.StringIO()
    with running.stage("next-run estimate", stream=stream, first=0.05, every=0.05):
        time.sleep(0.4)
    lines = lines_of(stream)
    assert len(lines) >= 3, lines
    assert all(re.fullmatch(r"progress next-run estimate: running for \d+ s", line) for line in lines[:-1])
    assert re.fullmatch(r"progress next-run estimate: done after \d+ s", lines[-1])


def test_a_quick_stage_and_a_quiet_one_say_nothing():
    quick, quiet = io.StringIO(), io.StringIO()
    with running.stage("quick", stream=quick, first=5.0):
        pass
    with running.stage("quiet", stream=quiet, enabled=False, first=0.01, every=0.01):
        time.sleep(0.1)
    assert quick.getvalue() == "" and quiet.getvalue() == ""


def test_a_failing_stage_raises_its_error_and_stops_telling():
    stream = io.StringIO()
    with pytest.raises(KeyboardInterrupt), running.stage("loading", stream=stream, first=0.02, every=0.02):
        time.sleep(0.1)
        raise KeyboardInterrupt
    said = len(lines_of(stream))
    time.sleep(0.1)
    assert len(lines_of(stream)) == said and lines_of(stream)[-1].startswith("progress loading: done after")
