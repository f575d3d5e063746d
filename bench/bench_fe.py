"""Benchmark of the headstock FE generator: time and peak memory vs mesh size.

For each mesh (the default of configs/paper_cycle.toml, one coarser and one
uniform refinement of the default) it records in a fresh process:

* nodes and elastic unknowns;
* the equilibrium thermal error at 2000 r/min (steady state) and its change
  against the next coarser mesh (mesh convergence);
* the seconds and peak resident memory of the steady solve plus the adjoint;
* the seconds and peak memory of the whole paper-cycle run (skipped for the
  refined mesh unless ``--full-refined``).

Usage::

    python bench/bench_fe.py [--full-refined]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "paper_cycle.toml"

MESHES = {
    "coarse": {"circumferential": 24, "radial": 3, "axial_spacing_m": 0.07},
    "default": {},
    "refined": {"refinements": 1},
}


def run_case(mesh_name: str, full_run: bool) -> dict:
    """Measure one mesh in this process (called in a child process)."""
    sys.path.insert(0, str(ROOT))
    from groupfit.fe import simulate_config
    from groupfit.fe.config import parse_config
    from groupfit.fe.geometry import FRONT_SEAT, REAR_SEAT, build_housing_mesh
    from groupfit.fe.headstock import ThermalModel, ThermoElasticModel, nose_error_gain

    config = tomllib.loads(CONFIG.read_text())
    config["mesh"] = {**config.get("mesh", {}), **MESHES[mesh_name]}
    scenario = parse_config(config)
    start = time.perf_counter()
    housing = build_housing_mesh(scenario.geometry, scenario.resolution)
    thermal = ThermalModel(housing, scenario.material, scenario.boundary)
    elastic = ThermoElasticModel(thermal.basis, scenario.material)
    gain = nose_error_gain(thermal, elastic, scenario.error_direction)
    heat = {FRONT_SEAT: scenario.bearings.front_W, REAR_SEAT: scenario.bearings.rear_W}
    ambient = scenario.ambient.mean_C
    steady = float(gain @ (thermal.steady_temperature(heat, ambient) - ambient))
    result = {
        "mesh": mesh_name,
        "nodes": int(housing.mesh.nvertices),
        "elastic_dofs": int(elastic.basis.N),
        "equilibrium_um": steady,
        "steady_s": time.perf_counter() - start,
        "steady_peak_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }
    del housing, thermal, elastic
    if full_run:
        start = time.perf_counter()
        frame = simulate_config(config, progress=False)
        result.update(
            run_s=time.perf_counter() - start,
            samples=len(frame),
            max_error_um=float(frame["error_um"].max()),
            run_peak_MB=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        )
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--full-refined", action="store_true", help="also run the whole paper cycle on the refined mesh"
    )
    parser.add_argument("--case", help=argparse.SUPPRESS)
    parser.add_argument("--full", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        print(json.dumps(run_case(args.case, args.full)))
        return

    rows = []
    for name in MESHES:
        full = name != "refined" or args.full_refined
        cmd = [sys.executable, __file__, "--case", name] + (["--full"] if full else [])
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        rows.append(json.loads(out.strip().splitlines()[-1]))

    header = (
        f"{'mesh':8} {'nodes':>7} {'el.dofs':>8} {'E_eq um':>9} {'change':>7} "
        f"{'steady s':>9} {'MB':>6} {'run s':>7} {'samples':>7} {'MB':>6}"
    )
    print(header)
    print("-" * len(header))
    previous = None
    for row in rows:
        change = "" if previous is None else f"{100 * (row['equilibrium_um'] - previous) / row['equilibrium_um']:+.2f}%"
        previous = row["equilibrium_um"]
        run = (
            f"{row['run_s']:7.1f} {row['samples']:7d} {row['run_peak_MB']:6.0f}"
            if "run_s" in row
            else f"{'-':>7} {'-':>7} {'-':>6}"
        )
        print(
            f"{row['mesh']:8} {row['nodes']:7d} {row['elastic_dofs']:8d} "
            f"{row['equilibrium_um']:9.3f} {change:>7} {row['steady_s']:9.1f} "
            f"{row['steady_peak_MB']:6.0f} {run}"
        )


if __name__ == "__main__":
    main()
