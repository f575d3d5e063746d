"""Cost of the exported C routine per sample, against a plain dot product in the same run.

    python bench/bench_c_step.py [--repeats 101] [--samples 4000] [--cc gcc]

Fits a grouped model with M = 8 temperatures and p = 6 breaks on a lumped
duty-cycle run (400 samples), exports it as C, compiles it with -O2 (double
and single precision) together with a timing driver, and feeds gf_step() the
modelling run over and over (gf_init() at the start of every pass, so every
switch window is crossed). Each repeat times --samples calls; the median over
the repeats is reported in ns per sample, next to the median of a plain
9-term dot product loop over the same inputs measured by the same program.
Prints the bytes of the state struct and of the constant tables (the .rodata
section of the compiled routine), and, for scale, the Python reference rule's
cost per sample.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from groupfit.data import load_run
from groupfit.export import render, write
from groupfit.models import GroupedRegressor
from groupfit.runtime import SwitchingRule
from groupfit.synthetic import simulate_lumped

SENSORS = {
    f"T{k + 1}": [tau, gain]
    for k, (tau, gain) in enumerate(
        [(300, 9.0), (500, 8.0), (900, 7.0), (1400, 6.0), (2200, 5.0), (3200, 4.5), (5000, 4.0), (7000, 3.5)]
    )
}

TIMER_C = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "groupfit_model.h"

static double now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

static int compare(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    int rows, repeats, samples, r, i, m;
    double *temps, *step_ns, *dot_ns, coef[GF_N_TEMPS + 1];
    volatile double sink = 0.0;
    gf_state state;
    if (argc < 3 || scanf("%d", &rows) != 1) return 2;
    repeats = atoi(argv[1]);
    samples = atoi(argv[2]);
    temps = malloc(sizeof(double) * (size_t)rows * GF_N_TEMPS);
    step_ns = malloc(sizeof(double) * (size_t)repeats);
    dot_ns = malloc(sizeof(double) * (size_t)repeats);
    for (i = 0; i < rows * GF_N_TEMPS; i++) if (scanf("%lf", &temps[i]) != 1) return 2;
    for (m = 0; m <= GF_N_TEMPS; m++) coef[m] = 0.5 + 0.01 * m;
    for (r = 0; r < repeats; r++) {
        double start, error_um, acc;
        int row = 0;
        gf_init(&state);
        start = now_ns();
        for (i = 0; i < samples; i++) {
            if (row == rows) { row = 0; gf_init(&state); }
            sink += gf_step(&state, &temps[row * GF_N_TEMPS], &error_um);
            sink += error_um;
            row++;
        }
        step_ns[r] = (now_ns() - start) / samples;
        row = 0;
        start = now_ns();
        for (i = 0; i < samples; i++) {
            const double *x = &temps[row * GF_N_TEMPS];
            if (++row == rows) row = 0;
            acc = coef[0];
            for (m = 0; m < GF_N_TEMPS; m++) acc = acc + coef[m + 1] * x[m];
            sink += acc;
        }
        dot_ns[r] = (now_ns() - start) / samples;
    }
    qsort(step_ns, (size_t)repeats, sizeof(double), compare);
    qsort(dot_ns, (size_t)repeats, sizeof(double), compare);
    printf("step_ns %.3f\ndot_ns %.3f\nstate_bytes %lu\nsink %g\n", step_ns[repeats / 2], dot_ns[repeats / 2],
           (unsigned long)sizeof(gf_state), (double)sink);
    free(temps); free(step_ns); free(dot_ns);
    return 0;
}
"""


def fitted_model():
    frame = simulate_lumped({"n_samples": 400, "sensors": SENSORS, "seed": 3})
    run = load_run(frame, temps=list(SENSORS), name="lumped8")
    estimator = GroupedRegressor(p=6, search="exact").fit(run.temps, run.error)
    return estimator.to_model_file(run), run


def rodata_bytes(obj: Path) -> int:
    """Size of the read-only data sections of an object file (the constant tables)."""
    out = subprocess.run(["size", "-A", str(obj)], capture_output=True, text=True, check=True).stdout
    return sum(int(m.group(1)) for m in re.finditer(r"^\.rodata\S*\s+(\d+)", out, flags=re.M))


def measure(folder: Path, temps: np.ndarray, cc: str, single: bool, repeats: int, samples: int) -> dict:
    tag = "float" if single else "double"
    define = ["-DGF_USE_FLOAT"] if single else []
    exe = folder / f"timer_{tag}"
    obj = folder / f"groupfit_model_{tag}.o"
    flags = [cc, "-std=c99", "-O2", *define]
    subprocess.run([*flags, "-c", str(folder / "groupfit_model.c"), "-o", str(obj)], check=True)
    subprocess.run([*flags, "-I", str(folder), str(folder / "timer.c"), str(obj), "-o", str(exe)], check=True)
    stdin = f"{len(temps)}\n" + "\n".join(" ".join(repr(float(v)) for v in row) for row in temps) + "\n"
    command = [str(exe), str(repeats), str(samples)]
    out = subprocess.run(command, input=stdin, capture_output=True, text=True, check=True)
    values = dict(line.split() for line in out.stdout.splitlines())
    return {
        "precision": tag,
        "step_ns": float(values["step_ns"]),
        "dot_ns": float(values["dot_ns"]),
        "state_bytes": int(values["state_bytes"]),
        "table_bytes": rodata_bytes(obj),
    }


def python_ns_per_sample(model: dict, temps: np.ndarray) -> float:
    rule = SwitchingRule(model)
    start = time.perf_counter()
    rule.replay(temps)
    return (time.perf_counter() - start) / len(temps) * 1e9


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=101)
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--cc", default="gcc")
    args = parser.parse_args(argv)

    model, run = fitted_model()
    print(
        f"model: M = {len(model.temps)} temperatures, p = {model.p} breaks, "
        f"{model.n_groups} groups; replaying {run.n_samples} samples, "
        f"{args.samples} gf_step calls per repeat, median of {args.repeats} repeats"
    )
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(render(model, "c"), folder)
        (folder / "timer.c").write_text(TIMER_C)
        rows = [measure(folder, run.temps, args.cc, single, args.repeats, args.samples) for single in (False, True)]
    header = ("build", "gf_step ns", "dot ns", "ratio", "state B", "tables B", "total B")
    print(f"{header[0]:8s} " + " ".join(f"{h:>{w}s}" for h, w in zip(header[1:], (11, 8, 6, 8, 9, 8))))
    for r in rows:
        print(
            f"{r['precision']:8s} {r['step_ns']:11.1f} {r['dot_ns']:8.1f} {r['step_ns'] / r['dot_ns']:6.2f} "
            f"{r['state_bytes']:8d} {r['table_bytes']:9d} {r['state_bytes'] + r['table_bytes']:8d}"
        )
    print(f"python reference rule: {python_ns_per_sample(model, run.temps):.0f} ns per sample")
    return 0


if __name__ == "__main__":
    sys.exit(main())
