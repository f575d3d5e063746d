"""The ball screw: the fin against the axisymmetric body, mesh convergence, and the
seed-003 model scored against the FE truth with and without measurement noise.

Prints, for configs/screw_H.toml without noise:

* the largest difference of the sensor temperatures and of the error at the
  probe between the 1-D fin (150 and 600 elements) and the 2-D axisymmetric
  body (two meshes), and the seconds each took;

then identifies the model on run H and scores it on runs A, B, C — once on the
shipped data sets (FE + noise) and once on the same runs regenerated without
noise (the bare FE truth) — for the source offset fitted and for x0 = 0 (the
formula as printed), next to the paper's figures scaled to each run.

Usage::

    python bench/bench_screw.py
"""

from __future__ import annotations

import time
import tomllib
from pathlib import Path

import numpy as np

from groupfit.fe import parse_config, simulate_config
from groupfit.fe.ballscrew import simulate_axisymmetric, simulate_ballscrew
from groupfit.screw import BallScrewModel
from groupfit.screw.compare import compare_screw
from groupfit.screw.runs import load_screw_run

ROOT = Path(__file__).resolve().parents[1]


def config(name: str, noise: bool = True) -> dict:
    raw = tomllib.loads((ROOT / "configs" / f"{name}.toml").read_text())
    if not noise:
        raw.pop("noise", None)
    return raw


def fin_vs_body() -> None:
    raw = config("screw_H", noise=False)
    fins = {}
    for elements in (150, 600):
        raw["mesh"]["elements"] = elements
        start = time.perf_counter()
        fins[elements] = simulate_ballscrew(parse_config(raw), progress=False)
        print(f"fin, {elements} P1 elements: {time.perf_counter() - start:.2f} s")
    sc = parse_config(config("screw_H", noise=False))
    fin = fins[150]
    names = list(sc.sensors)
    rise = fin[names].to_numpy().max() - sc.ambient_C
    print(
        f"fin 150 vs 600 elements: max |ΔT| {np.abs(fins[600][names].to_numpy() - fin[names].to_numpy()).max():.2e} K, "
        f"max |Δe| {np.abs(fins[600]['error_um'] - fin['error_um']).max():.2e} µm"
    )
    for axial, radial in ((150, 3), (300, 8)):
        start = time.perf_counter()
        body = simulate_axisymmetric(sc, axial=axial, radial=radial)
        seconds = time.perf_counter() - start
        d_t = np.abs(body["temps"] - fin[names].to_numpy()).max()
        d_e = np.abs(body["error_um"] - fin["error_um"].to_numpy()).max()
        print(
            f"axisymmetric {axial}×{radial} Q1 ({seconds:.1f} s) vs fin: max |ΔT| at the surface sensors "
            f"{d_t:.4f} K ({100 * d_t / rise:.3f} % of the {rise:.2f} K peak rise), max |Δe| at 16 cm {d_e:.4f} µm "
            f"({100 * d_e / fin['error_um'].max():.3f} % of {fin['error_um'].max():.2f} µm)"
        )


def score(label: str, runs: dict, offset) -> None:
    model = BallScrewModel(source_offset=offset)
    result = compare_screw(model, runs["H"], [runs[n] for n in "ABC"])
    a0, a1 = model.alpha_prime_
    print(
        f"\n{label}, x0 {'fitted' if offset == 'fit' else '= ' + str(offset)}: h = {model.h_:.3f} W/(m²·K) "
        f"(FE 17.2, paper 17.2), α′ = {a0 * 1e5:.3f} + {a1 * 1e5:.4f}·τ0 (1e-5 m²/s), "
        f"x0 = {1e3 * model.source_offset_:.1f} mm"
    )
    print(f"{'run':<9}{'C1':>7}{'C2':>7}{'max ΔT':>9}{'after t_r':>11}{'max |e|':>9}{'MLR':>7}   paper scaled ΔT / e")
    index = {(s.model, s.run): s for s in result.scores}
    for name, run in runs.items():
        s, m = index[("screw", run.name)], index[("mlr", run.name)]
        entry = model.sources_[run.name]
        p = s.paper
        print(
            f"{name:<9}{entry['C1']:>7.2f}{entry['C2']:>7.2f}{s.max_temp_K:>8.2f}K{s.max_temp_after_tr_K:>10.2f}K"
            f"{s.max_um:>8.2f}µ{m.max_um:>7.2f}   {p['max_temp_K_scaled']:.2f} K / {p['max_um_scaled']:.2f} µm"
        )


def main() -> None:
    fin_vs_body()
    shipped = {n: load_screw_run(ROOT / "datasets" / f"screw_{n}.csv") for n in "HABC"}
    bare = {
        n: load_screw_run(simulate_config(config(f"screw_{n}", noise=False), progress=False), name=f"screw_{n}")
        for n in "HABC"
    }
    for offset in ("fit", 0.0):
        score("shipped data (FE + noise)", shipped, offset)
        score("FE truth without noise", bare, offset)


if __name__ == "__main__":
    main()
