"""A run logged by LabVIEW, DIAdem or a NI data logger (``.tdms``): its channels as the columns of a table.

Every channel of numbers or time stamps becomes a column named as the
channel (``Group/Channel`` when two groups hold a channel of the same name),
in the file's order; the channels of the most common length make the run,
and a channel of another length (a probe sampled at another rate) is left out
and named in the refusal if it is asked for. A log without a time channel
gets ``time_s`` from its channels' waveform timing (``wf_start_offset``,
``wf_increment``, in seconds). A channel's ``unit_string`` (``mm``, ``°F``,
``min``) is read as a logger's row of units under the header
(:mod:`groupfit.units_row`): converted to µm, °C or s with a note. Reading
needs the package ``npTDMS`` (``pip install "groupfit[tdms]"``).
"""

from __future__ import annotations

import logging
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.errors import InputError, first_line
from groupfit.timestamps import time_like_columns

EXPORT = "export the log from LabVIEW or DIAdem as CSV"


def read_tdms(path: Path, label: str) -> pd.DataFrame:
    """The channels of a TDMS file as a table (module docstring); refused in one line when it holds none."""
    from nptdms import TdmsFile  # an optional dependency: ImportError tells the reader to install it

    readers = [log for name, log in logging.Logger.manager.loggerDict.items() if name.split(".")[0] == "nptdms"]
    levels = [(log, log.level) for log in readers if isinstance(log, logging.Logger)]
    for log, _ in levels:  # a cut-short file is refused below in one line, not warned about by the reader too
        log.setLevel(logging.ERROR)
    try:
        tdms = TdmsFile.read(path)
        channels = [(group.name, channel) for group in tdms.groups() for channel in group.channels()]
        values = {(group, channel.name): channel[:] for group, channel in channels}
    except (ValueError, KeyError, IndexError, EOFError, OSError, TypeError) as exc:
        raise InputError(f"{label}: not a readable TDMS file ({first_line(exc)}); {EXPORT}") from None
    finally:
        for log, level in levels:
            log.setLevel(level)
    usable = [
        (group, channel)
        for group, channel in channels
        if np.asarray(values[(group, channel.name)]).dtype.kind in "biufM" and len(channel) > 1
    ]
    if not usable:
        raise InputError(f"{label}: holds no channel of numbers or time stamps; {EXPORT}")
    lengths = Counter(len(channel) for _, channel in usable)
    length = max(lengths, key=lambda n: (lengths[n], n))
    kept = [(group, channel) for group, channel in usable if len(channel) == length]
    counts = Counter(channel.name for _, channel in kept)
    names = [channel.name if counts[channel.name] == 1 else f"{group}/{channel.name}" for group, channel in kept]
    frame = pd.DataFrame({name: values[(group, channel.name)] for name, (group, channel) in zip(names, kept)})
    units = {name: str(channel.properties.get("unit_string", "")) for name, (_, channel) in zip(names, kept)}
    if not time_like_columns(frame.columns):
        time = _waveform_time(kept, length)
        if time is not None:
            frame.insert(0, "time_s", time)
            units["time_s"] = "s"
    frame.attrs["text_rows"] = [{name: unit for name, unit in units.items() if unit}]
    return frame


def _waveform_time(channels, length: int) -> np.ndarray | None:
    """Seconds of each sample from the channels' waveform timing, when they share it; None otherwise."""
    timings = {
        (float(channel.properties.get("wf_start_offset", 0.0)), float(channel.properties["wf_increment"]))
        for _, channel in channels
        if "wf_increment" in channel.properties
    }
    if len(timings) != 1:
        return None
    start, increment = timings.pop()
    if not increment > 0:
        return None
    return start + increment * np.arange(length)


__all__ = ["read_tdms"]
