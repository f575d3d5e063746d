"""Drive an exported C routine from Python: build it with a small driver, feed it samples.

The driver reads one sample per line (``GF_N_TEMPS`` numbers in any form
``strtod`` reads: decimal, hexadecimal floats, ``nan``, ``inf``), or the word
``reset``, and prints per sample the return code, the group, the fault bits,
the switch code, the prediction and the compensation, the last two as C99
hexadecimal floats (``%a``) so that nothing is lost. It is how the tests hold
the C build to the Python rule, and a way to check the export on another
compiler.
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

DRIVER_C = r"""/* groupfit_driver.c - feed gf_step() from stdin, print its decisions. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "groupfit_model.h"

int main(void)
{
    static char line[65536];
    gf_state state;
    gf_init(&state);
    while (fgets(line, (int)sizeof line, stdin) != NULL) {
        double temps[GF_N_TEMPS];
        double error_um = 0.0;
        char *cursor = line;
        int m;
        int code;
        if (strncmp(line, "reset", 5) == 0) {
            gf_init(&state);
            continue;
        }
        for (m = 0; m < GF_N_TEMPS; m++) {
            char *end;
            temps[m] = strtod(cursor, &end);
            if (end == cursor) {
                fprintf(stderr, "groupfit_driver: expected %d numbers per line\n", GF_N_TEMPS);
                return 2;
            }
            cursor = end;
        }
        code = gf_step(&state, temps, &error_um);
        printf("%d %d %d %d %a %a\n", code, state.group, state.fault, state.switched, error_um,
               (double)state.comp_um);
    }
    return 0;
}
"""

STRICT_FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic")


@dataclass(frozen=True)
class DriverOutput:
    """Decisions of the C routine, one entry per sample."""

    code: np.ndarray
    group: np.ndarray
    fault: np.ndarray
    switched: np.ndarray
    prediction_um: np.ndarray
    compensation_um: np.ndarray

    @classmethod
    def from_rows(cls, rows: Sequence[Sequence[str]]) -> "DriverOutput":
        """The decisions of the driver's sample lines, each ``code group fault switched prediction compensation``
        (the two reals in hexadecimal)."""
        return cls(
            code=np.array([int(r[0]) for r in rows]),
            group=np.array([int(r[1]) for r in rows]),
            fault=np.array([int(r[2]) for r in rows]),
            switched=np.array([int(r[3]) for r in rows]),
            prediction_um=np.array([float.fromhex(r[4]) for r in rows]),
            compensation_um=np.array([float.fromhex(r[5]) for r in rows]),
        )


def build_driver(
    export_dir: str | Path,
    executable: str | Path,
    *,
    single: bool = False,
    flags: Sequence[str] = ("-O2",),
    compiler: str = "gcc",
    driver_source: str = DRIVER_C,
) -> Path:
    """Compile ``groupfit_model.c`` of ``export_dir`` with the driver; return the executable.

    Raises ``subprocess.CalledProcessError`` (with the compiler's messages in
    ``stderr``) when the build fails.
    """
    export_dir = Path(export_dir)
    driver = export_dir / "groupfit_driver.c"
    driver.write_text(driver_source, encoding="ascii")
    command = [
        compiler,
        *STRICT_FLAGS,
        *flags,
        *(["-DGF_USE_FLOAT"] if single else []),
        "-I",
        str(export_dir),
        str(driver),
        str(export_dir / "groupfit_model.c"),
        "-o",
        str(executable),
        "-lm",  # pow and fabs of a power stage (a model without one uses no library)
    ]
    subprocess.run(command, check=True, capture_output=True, text=True)
    return Path(executable)


def stream_text(streams: Sequence[np.ndarray]) -> str:
    """Driver input: each (N, k) array after a ``reset`` line, values as exact hexadecimal floats."""
    lines = []
    for readings in streams:
        lines.append("reset")
        for row in np.asarray(readings, dtype=float):
            lines.append(" ".join(_number(v) for v in row))
    return "\n".join(lines) + "\n"


def _number(value: float) -> str:
    value = float(value)
    if np.isnan(value):
        return "nan"
    if np.isinf(value):
        return "inf" if value > 0 else "-inf"
    return value.hex()


def run_driver(executable: str | Path, streams: Sequence[np.ndarray], timeout: float = 60.0) -> list[DriverOutput]:
    """Run the driver over several streams (each starting from ``gf_init``)."""
    result = subprocess.run(
        [str(executable)], input=stream_text(streams), capture_output=True, text=True, timeout=timeout, check=True
    )
    rows = [line.split() for line in result.stdout.splitlines()]
    outputs, start = [], 0
    for readings in streams:
        chunk = rows[start : start + len(readings)]
        start += len(readings)
        outputs.append(DriverOutput.from_rows(chunk))
    if start != len(rows):
        raise RuntimeError(f"driver printed {len(rows)} lines for {start} samples")
    return outputs
