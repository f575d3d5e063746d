"""A line every so often while a stage without progress of its own runs, so a long log is never silent for minutes."""

from __future__ import annotations

import sys
import threading
import time
from contextlib import contextmanager

FIRST_SECONDS = 10.0
"""A stage done sooner says nothing."""
EVERY_SECONDS = 30.0
"""Time between two lines of a stage still running."""


@contextmanager
def stage(name: str, *, enabled: bool = True, stream=None, first: float = FIRST_SECONDS, every: float = EVERY_SECONDS):
    """Run the body as the stage ``name``: after ``first`` seconds, and every ``every`` seconds after that, a line
    ``progress NAME: running for T s`` on ``stream`` (stderr); when the stage ends after having said so, the line
    ``progress NAME: done after T s``. Nothing when ``enabled`` is false or the stage ends within ``first``."""
    if not enabled:
        yield
        return
    stream = stream or sys.stderr
    started = time.monotonic()
    finished = threading.Event()
    said = threading.Event()

    def tell() -> None:
        wait = first
        while not finished.wait(wait):
            print(f"progress {name}: running for {time.monotonic() - started:.0f} s", file=stream, flush=True)
            said.set()
            wait = every

    teller = threading.Thread(target=tell, name=f"groupfit progress {name}", daemon=True)
    teller.start()
    try:
        yield
    finally:
        finished.set()
        teller.join()
        if said.is_set():
            print(f"progress {name}: done after {time.monotonic() - started:.0f} s", file=stream, flush=True)


__all__ = ["stage"]
