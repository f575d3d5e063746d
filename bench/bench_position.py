"""Position models on the moving-nut ball screw: K0 + tanb (P - P0) and polynomials against a position-free model.

The FE run ``configs/screw_nut.toml`` with ``[probe] displacements_m`` at
0, 50, …, 300 mm writes the screw's exact displacement at those positions
(``u<mm>mm_um``). Check runs every ``--every`` samples (default 12: every
2 min of the 10 s run) read them with 0.1 µm Gaussian interferometer noise and
0.01 µm quantisation: a wide table ``err_P<mm>``, fitted with

    groupfit fit --data wide.csv --position P_mm --reference start --p 0 --position-order N|auto

and scored per position (RMS and max over the check runs). The position-free
model is the least-squares fit of the same inputs to every row.

    python bench/bench_position.py [--every 12] [--out /tmp/position_bench]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
POSITIONS_M = [0.0, 0.05, 0.10, 0.15, 0.20, 0.25, 0.30]


VALIDATION = {
    "programme = [[0.25, 0.1, 2.0], [0.05, 0.1, 2.0]]": "programme = [[0.25, 0.05, 2.0], [0.10, 0.05, 2.0]]",
    "seed = 5": "seed = 6",
}
"""The held-out run: the nut strokes 100-250 mm at half the speed, other sensor noise."""


def simulate(out: Path, changes: dict[str, str] | None = None, name: str = "screw_nut_field") -> pd.DataFrame:
    text = (ROOT / "configs" / "screw_nut.toml").read_text()
    for old, new in (changes or {}).items():
        if old not in text:
            raise SystemExit(f"configs/screw_nut.toml no longer holds {old!r}")
        text = text.replace(old, new)
    line = 'x_m = "nut"'
    field = f"{line}\ndisplacements_m = [{', '.join(f'{x:.2f}' for x in POSITIONS_M)}]"
    config = out / f"{name}.toml"
    config.write_text(text.replace(line, field))
    csv = out / f"{name}.csv"
    subprocess.run(
        [sys.executable, "-m", "groupfit", "simulate", str(config), "-o", str(csv)], check=True, capture_output=True
    )
    return pd.read_csv(csv)


def wide_table(frame: pd.DataFrame, every: int, seed: int = 13) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    rows = frame.iloc[::every].reset_index(drop=True)
    temps = [c for c in frame.columns if c.startswith("T") and c.endswith("mm")]
    wide = rows[["time_s", *temps]].copy()
    for x in POSITIONS_M:
        mm = int(round(x * 1000))
        exact = rows[f"u{mm}mm_um"].to_numpy()
        wide[f"err_P{mm:04d}"] = np.round(exact + rng.normal(0.0, 0.1, len(exact)), 2)
    return wide


def fit(wide: Path, out: Path, *options: str) -> dict:
    argv = [sys.executable, "-m", "groupfit", "fit", "--data", str(wide), "--position", "P_mm", "--reference", "start"]
    argv += ["--p", "0", "--quiet", "--out", str(out), *options]
    report = subprocess.run(argv, check=True, capture_output=True, text=True)
    return {"model": json.loads((out / "model.json").read_text()), "report": report.stderr + report.stdout}


def scores(residuals: np.ndarray, position: np.ndarray) -> dict:
    out = {}
    for p in np.unique(position):
        r = residuals[position == p]
        out[f"{p:g}"] = (float(np.sqrt(np.mean(r**2))), float(np.max(np.abs(r))))
    out["all"] = (float(np.sqrt(np.mean(residuals**2))), float(np.max(np.abs(residuals))))
    return out


def controller_rate(folder: Path, field: pd.DataFrame, label: str) -> str:
    """The model fitted on the 2 min check runs replayed on the simulation's own 10 s stream.

    The axis visits the measured positions in turn, one per sample; the error
    is the exact displacement there (no probe noise).
    """
    temps = [c for c in field.columns if c.startswith("T") and c.endswith("mm")]
    stream = field[["time_s", *temps]].copy()
    mm = np.array([int(round(x * 1000)) for x in POSITIONS_M])
    at = mm[np.arange(len(stream)) % len(mm)]
    stream["P_mm"] = at.astype(float)
    stream["error_um"] = [field[f"u{p}mm_um"].iloc[k] for k, p in enumerate(at)]
    stream.to_csv(folder / "stream_10s.csv", index=False)
    argv = [sys.executable, "-m", "groupfit", "replay", str(folder / "model.json"), "--data"]
    report = subprocess.run([*argv, str(folder / "stream_10s.csv"), "--json", "-"], check=True, capture_output=True)
    result = json.loads(report.stdout)
    return (
        f"{label}: replayed at {result['sampling_period_s']:g} s (fitted at {result['model_period_s']:g} s) on "
        f"{result['n_samples']} samples: RMS {result['rms_um']:.3f} um, max {result['max_um']:.3f} um"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=int, default=12)
    parser.add_argument("--out", default="/tmp/position_bench")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    from groupfit.model import ModelFile
    from groupfit.position import fit_blocks, load_position_run

    field = simulate(out)
    wide = wide_table(field, args.every)
    wide.to_csv(out / "screw_nut_wide.csv", index=False)
    held = wide_table(simulate(out, VALIDATION, "screw_nut_validation"), args.every, seed=14)
    held.to_csv(out / "screw_nut_validation_wide.csv", index=False)
    temps = [c for c in wide.columns if c.startswith("T")]
    names = ("screw_nut_wide", "screw_nut_validation_wide")
    runs = {name: load_position_run(out / f"{name}.csv", "P_mm", temps=temps) for name in names}
    run = runs["screw_nut_wide"]
    inputs = {name: (r.run.temps - r.run.temps[0])[r.check] for name, r in runs.items()}
    free = fit_blocks(inputs["screw_nut_wide"], np.zeros(len(run.position)), run.error, 0)[0]
    table = {
        name: {"position-free": scores(r.error - (free[0] + inputs[name] @ free[1:]), r.position)}
        for name, r in runs.items()
    }
    for label, options in [("K0 + tanb", ("--position-order", "1")), ("auto", ("--position-order", "auto"))]:
        result = fit(out / "screw_nut_wide.csv", out / label.replace(" ", "_"), *options)
        model = ModelFile.from_dict(result["model"])
        print(controller_rate(out / label.replace(" ", "_"), field, label))
        name = f"{label} (order {model.position.order})"
        for data, r in runs.items():
            prediction = model.predict_position(inputs[data], r.position, np.zeros(len(r.position), dtype=int))
            table[data][name] = scores(r.error - prediction, r.position)
        print("\n".join(result["report"].strip().splitlines()[-3:-1]))
    for data, rows in table.items():
        r = runs[data]
        print(f"\n{data}: {r.run.n_samples} check runs x {len(r.positions)} positions")
        print("RMS / max |residual| (um) at each position (mm)")
        positions = [f"{p:g}" for p in r.positions] + ["all"]
        print(f"{'model':<22}" + "".join(f"{p:>14}" for p in positions))
        for name, row in rows.items():
            print(f"{name:<22}" + "".join(f"{row[p][0]:>7.3f}/{row[p][1]:<6.3f}" for p in positions))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
