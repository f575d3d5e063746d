"""One validated run: the arrays a model reads and the table they came from (:func:`groupfit.data.load_run`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from groupfit.default_columns import DEFAULT_TIME


@dataclass(frozen=True)
class Run:
    """One validated run."""

    name: str
    """Short name (the file stem, or the name given for a DataFrame)."""
    source: str
    """Where the run came from, used in messages."""
    time: np.ndarray
    """Sample times in seconds, strictly increasing, shape (N,)."""
    temps: np.ndarray
    """Model input temperatures in °C, shape (N, k), in the order of ``temp_names``."""
    temp_names: tuple[str, ...]
    error: np.ndarray | None
    """Thermal error in µm, shape (N,), when the run has the error column."""
    error_name: str | None
    period: float
    """Sampling period in seconds (median interval)."""
    frame: pd.DataFrame = field(repr=False)
    """The whole table, including columns that are not model inputs; readings as recorded."""
    time_name: str = DEFAULT_TIME
    reference: str | None = None
    """What ``temps`` are relative to (:mod:`groupfit.reference`): None for absolute readings (as loaded), a
    column or ``"start"`` once :func:`groupfit.reference.with_reference` has applied it."""
    notes: tuple[str, ...] = ()
    """What loading did to the log (a jittering clock accepted, readings resampled), one line each."""
    clock_origin_s: float | None = None
    """The date-time ``time`` counts from, in seconds since 1970, when the log's stamps were dates (None: a clock
    of its own, in seconds), in the clock of the run's last row (a local clock's changes to and from summer time
    read through, :mod:`groupfit.clock_changes`); a file whose stamps go on from another's continues it."""
    clock_shift_s: float | None = None
    """For a log stamped in local wall-clock time without a UTC offset: the seconds its clock's changes to and
    from summer time added to its first row's wall-clock time to express it in the last row's clock (0.0 where
    its clock did not change; −3600.0 across the end of summer time). None: a clock that places itself (a UTC
    offset or a zone in its stamps) or one of its own."""

    @property
    def n_samples(self) -> int:
        return len(self.time)

    @property
    def first_clock_origin_s(self) -> float | None:
        """:attr:`clock_origin_s` in the clock of the run's first row: ``time[0]`` after it is the first row's
        wall-clock date-time, which a file that the run goes on from ended a sampling period before."""
        if self.clock_origin_s is None:
            return None
        return self.clock_origin_s - (self.clock_shift_s or 0.0)


__all__ = ["Run"]
