"""The deployable AR(1) model on the shared measured test: free-run RMS over Δτ, fit and start.

On ``../shared/data/fl_thermal/spindle_step_test.csv`` (15 s sampling, speed
steps 0 / 1250 / 0 / 2500 / 0 / 3750 / 0 / 5000 r/min, 4 h each; probe
``disp_ch3_um``) fits ``groupfit fit --model ar1 --heat spindle_rpm`` at
Δτ = 15, 30 and 60 s, by least squares on the one-step equations and on the
free-run error, with the free run started from 0 (the paper's ΔL(0) = 0) and
from the measured error, and prints per row C1, the free-run RMS, the largest
error and the prediction accuracy on the same run (in sample: the test's
unseen 40 % is not part of the shared file), and the one-step RMS.

Then scores each model fitted on the first half of the file (0, 1250, 0, 2500
r/min) on the second half (3750, 5000 r/min: levels it has not seen, C2 by the
heat law ``(q/level)^(5/3)``), free-running from 0 at the second half's start.

Skips with a message when ``../shared`` is absent. Usage::

    python bench/bench_ar1_measured.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from groupfit.ar1.fitting import decimate, decimation_step, fit_ar1_file
from groupfit.ar1.rule import AR1Rule
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.metrics import prediction_accuracy

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
PERIODS = (15.0, 30.0, 60.0)
FITS = ("one_step", "free_run")
STARTS = ("zero", "measured")


def main() -> None:
    if not DATA.is_file():
        print(f"skipped: {DATA} is absent")
        return
    run = load_run(DATA, temps=[], error="disp_ch3_um")
    heat_raw = run.frame["spindle_rpm"].to_numpy(dtype=float)
    half = int(np.argmax(heat_raw >= 3750))
    print(f"{DATA.name}: {run.n_samples} samples every {run.period:g} s; second half from row {half + 1}")
    header = f"{'dtau s':>6} {'fit':>9} {'start':>9} {'C1':>9} {'RMS um':>8} {'max um':>8} {'acc %':>6} {'1-step':>7}"
    header += f" {'2nd half RMS':>12} {'acc %':>6} {'s':>5}"
    print(header)
    for period in PERIODS:
        step = decimation_step(run.period, period)
        heat, error = decimate(heat_raw, step), decimate(run.error, step)
        cut = half // step
        for fit in FITS:
            for start in STARTS:
                began = time.perf_counter()
                options = dict(period_s=period, heat_name="spindle_rpm", error_name="disp_ch3_um", source=DATA.name)
                try:
                    whole = fit_ar1_file(heat, error, fit_method=fit, start=start, **options)
                    first = fit_ar1_file(heat[:cut], error[:cut], fit_method=fit, start=start, **options)
                except InputError as exc:
                    print(f"{period:>6g} {fit:>9} {start:>9}  refused: {exc}")
                    continue
                second = AR1Rule(first.model).replay(heat[cut:], initial_um=0.0 if start == "zero" else error[cut])
                residual = error[cut:] - second.prediction_um
                s = whole.scores
                print(
                    f"{period:>6g} {fit:>9} {start:>9} {whole.model.c1:>9.6f} {s['rms_um']:>8.3f} {s['max_um']:>8.2f} "
                    f"{s['accuracy_percent']:>6.1f} {s['one_step_rms_um']:>7.3f} "
                    f"{np.sqrt(np.mean(residual**2)):>12.3f} {prediction_accuracy(error[cut:], residual):>6.1f} "
                    f"{time.perf_counter() - began:>5.1f}"
                )


if __name__ == "__main__":
    main()
