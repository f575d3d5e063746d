"""What the tests of local clocks share: the CLI's exit status, and the skip where no tz database is at hand."""

from __future__ import annotations

import zoneinfo

import pytest

from groupfit.cli import main

needs_zones = pytest.mark.skipif(not zoneinfo.available_timezones(), reason="no tz database at hand")


def cli(*args) -> int:
    """The exit status of ``groupfit ARGS`` (2 for a refusal), run in this process."""
    try:
        return main([str(a) for a in args])
    except SystemExit as exc:
        return int(exc.code)
