"""Drive an exported C routine with probe checks: ``gf_step()`` per sample, ``gf_probe()`` where a check falls.

The driver (:data:`PROBE_DRIVER_C`, built by :func:`groupfit.export.harness.build_driver`
with ``driver_source=PROBE_DRIVER_C``) reads what :mod:`groupfit.export.harness`'s
driver reads, plus lines ``probe VALUE`` (a check after the last sample), and
prints ``P CODE`` for each check, so a test holds ``gf_probe`` to
:meth:`groupfit.runtime.SwitchingRule.probe` as well as the samples to the rule.
"""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Sequence

import numpy as np

from groupfit.export.harness import DRIVER_C, DriverOutput, _number

PROBE_DRIVER_C = DRIVER_C.replace(
    """        if (strncmp(line, "reset", 5) == 0) {""",
    """        if (strncmp(line, "probe", 5) == 0) {
            printf("P %d\\n", gf_probe(&state, strtod(line + 5, NULL)));
            continue;
        }
        if (strncmp(line, "reset", 5) == 0) {""",
)


def probe_stream_text(streams: Sequence[np.ndarray], probes: Sequence[np.ndarray]) -> str:
    """Driver input: each stream after ``reset``; after row i a ``probe`` line where ``probes[i]`` is not NaN."""
    lines = []
    for readings, checks in zip(streams, probes):
        lines.append("reset")
        for row, check in zip(np.asarray(readings, dtype=float), np.asarray(checks, dtype=float)):
            lines.append(" ".join(_number(v) for v in row))
            if not np.isnan(check):
                lines.append("probe " + _number(check))
    return "\n".join(lines) + "\n"


def run_probe_driver(
    executable: str | Path, streams: Sequence[np.ndarray], probes: Sequence[np.ndarray], timeout: float = 60.0
) -> list[tuple[DriverOutput, np.ndarray]]:
    """Per stream the samples' decisions and the codes ``gf_probe`` returned, in order."""
    result = subprocess.run(
        [str(executable)],
        input=probe_stream_text(streams, probes),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=True,
    )
    rows = [line.split() for line in result.stdout.splitlines()]
    out, start = [], 0
    for readings, checks in zip(streams, probes):
        n_lines = len(readings) + int(np.sum(~np.isnan(np.asarray(checks, dtype=float))))
        chunk = rows[start : start + n_lines]
        start += n_lines
        samples = [r for r in chunk if r[0] != "P"]
        codes = np.array([int(r[1]) for r in chunk if r[0] == "P"], dtype=int)
        out.append((DriverOutput.from_rows(samples), codes))
    return out


__all__ = ["PROBE_DRIVER_C", "probe_stream_text", "run_probe_driver"]
