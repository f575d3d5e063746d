"""Byte snapshots of the CLI's outputs: fit, export, diagnose on the ``configs/diag_*`` data sets and the paper cycle.

:func:`produce` runs the scenarios below through ``groupfit.cli.main`` and
returns every output it wrote — the model files, every export target, the
``--json`` results and the printed reports — as bytes, keyed by a path
relative to the snapshot folder. Paths are written as ``<out>`` and
``<data>`` (a path from the model file's folder as ``<from model>``);
timings (a search's, an estimate's) as ``<t> s``. Figures (PNG) are left
out: their bytes depend on the matplotlib version.

A change meant to alter an output (a new report line, a new model key)
regenerates the snapshots with one command, from the repository's root::

    python -m tests.snapshots --update

then ``git diff tests/data/snapshots`` shows what changed.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import re
import shutil
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets"
SNAPSHOTS = Path(__file__).resolve().parent / "data" / "snapshots"
TEMPS = "T1,T2,T3,T4"
TIMING = re.compile(rb"\b\d+(\.\d+)?(e-?\d+)? s\b")
SECONDS = re.compile(rb'"seconds": [-+0-9.eE]+')
FROM_MODEL = re.compile(rb'"path_from_model": "[^"]*"')
"""A data file's path from the model file's folder: it depends on where the temporary folder lies."""


def position_run(path: Path) -> Path:
    """A small long position table (three check positions, a heating and cooling run), noise by a fixed formula."""
    t = np.arange(0, 40) * 600.0
    t1 = 20 + 6 * (1 - np.exp(-t / 7000.0)) - 2 * (t > 15000) * (1 - np.exp(-(t - 15000) / 5000.0))
    t2 = 21 + 3 * (1 - np.exp(-t / 12000.0))
    rows = []
    for i in range(len(t)):
        for k, p in enumerate((0.0, 250.0, 500.0)):
            d = p - 250.0
            error = 1.2 * (t1[i] - 20) + 0.4 * (t2[i] - 21) + (0.011 * (t1[i] - 20) + 0.003 * (t2[i] - 21)) * d
            rows.append((t[i], p, round(t1[i], 3), round(t2[i], 3), round(error + 0.1 * np.sin(1.7 * i + k), 3)))
    pd.DataFrame(rows, columns=["time_s", "P_mm", "T1", "T2", "error_um"]).to_csv(path, index=False)
    return path


def cli(args: list[str]) -> bytes:
    """Run the CLI in this process; its printed report."""
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        status = main(args)
    if status != 0:
        raise RuntimeError(f"groupfit {' '.join(args)} exited {status}")
    return buffer.getvalue().encode()


def fit_p0(out: Path, scenario: str, *extra: str) -> bytes:
    csv = str(DATA / f"diag_{scenario}_model.csv")
    return cli(["fit", "--data", csv, "--temps", TEMPS, "--p", "0", *extra, "--out", str(out)])


def diagnose(out: Path, model: Path, scenario: str, *extra: str) -> bytes:
    data, validate = (str(DATA / f"diag_{scenario}_{kind}.csv") for kind in ("model", "validate"))
    return cli(
        ["diagnose", str(model), "--data", data, "--validate", validate, *extra]
        + ["--out", str(out), "--json", str(out / "diagnose.json")]
    )


def export_all(model: Path, out: Path) -> bytes:
    return cli(["export", str(model), "--target", "all", "--out", str(out)])


def diag_scenario(scenario: str, *, reference: str = "none", export: bool = False, options: tuple = ()):
    """Fit a global model on the scenario's modelling run, diagnose it, export the augmented model if asked."""

    def run(out: Path) -> None:
        (out / "fit.txt").write_bytes(fit_p0(out / "fit", scenario, "--reference", reference))
        report = diagnose(out / "diagnose", out / "fit" / "model.json", scenario, *options)
        (out / "diagnose.txt").write_bytes(report)
        augmented = out / "diagnose" / "model_augmented.json"
        if export and augmented.exists():
            (out / "export.txt").write_bytes(export_all(augmented, out / "export"))

    return run


def paper(out: Path) -> None:
    """The paper cycle: a grouped model (p = 2, exact search), every export target, its diagnosis."""
    fit = ["fit", "--data", str(DATA / "paper_cycle.csv"), "--temps", TEMPS, "--p", "2", "--search", "exact"]
    (out / "fit.txt").write_bytes(cli([*fit, "--out", str(out / "fit"), "--json", str(out / "fit.json")]))
    (out / "export.txt").write_bytes(export_all(out / "fit" / "model.json", out / "export"))
    report = cli(
        ["diagnose", str(out / "fit" / "model.json"), "--data", str(DATA / "paper_cycle.csv")]
        + ["--validate", str(DATA / "validation_speed.csv"), "--out", str(out / "diagnose")]
        + ["--json", str(out / "diagnose" / "diagnose.json")]
    )
    (out / "diagnose.txt").write_bytes(report)


def position(out: Path) -> None:
    """A position model (E(P, T), order 1) and its export, position table included."""
    out.mkdir(parents=True, exist_ok=True)
    csv = position_run(out / "position.csv")
    fit = ["fit", "--data", str(csv), "--temps", "T1,T2", "--p", "0", "--position", "P_mm", "--reference", "none"]
    (out / "fit.txt").write_bytes(cli([*fit, "--out", str(out / "fit")]))
    (out / "export.txt").write_bytes(export_all(out / "fit" / "model.json", out / "export"))


SCENARIOS: dict[str, Callable[[Path], None]] = {
    "paper": paper,
    "position": position,
    "diag_none": diag_scenario("none"),
    "diag_ambient": diag_scenario("ambient", export=True),
    "diag_lag": diag_scenario("lag", export=True),
    "diag_speed": diag_scenario("speed"),
    "diag_ambient_reference": diag_scenario("ambient", reference="T_amb"),
    "diag_lag_reference": diag_scenario("lag", reference="T_amb"),
    "diag_speed_forward": diag_scenario("speed", options=("--select", "forward")),
    "diag_speed_joint": diag_scenario("speed", options=("--select", "joint")),
    "diag_source_ridge": diag_scenario("source", options=("--ridge", "auto")),
}
"""Each scenario writes into its own folder; every file but the figures is a snapshot."""
FAST = ("position", "diag_lag", "diag_ambient_reference", "diag_lag_reference")
"""The scenarios of the fast lane (a few seconds together): every export target, the position table, a fitted and
an augmented model, a reference dropped before the effects and one kept after the diagnosis on absolute readings."""


def normalised(data: bytes, out: Path) -> bytes:
    data = data.replace(str(out).encode(), b"<out>").replace(str(DATA).encode(), b"<data>")
    data = SECONDS.sub(b'"seconds": "<t>"', data)
    data = FROM_MODEL.sub(b'"path_from_model": "<from model>"', data)
    return b"\n".join(
        TIMING.sub(b"<t> s", line) if line.startswith((b"search", b"breaks")) else line for line in data.split(b"\n")
    )


def produce(names: list[str] | None = None) -> dict[str, bytes]:
    """The outputs of the scenarios ``names`` (default: all), keyed by ``scenario/relative/path``."""
    found = {}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp).resolve()
        for name in names or list(SCENARIOS):
            folder = out / name
            folder.mkdir()
            SCENARIOS[name](folder)
            for path in sorted(folder.rglob("*")):
                if path.is_file() and path.suffix != ".png":
                    found[path.relative_to(out).as_posix()] = normalised(path.read_bytes(), out)
    return found


def stored(names: list[str] | None = None) -> dict[str, bytes]:
    """The snapshots on disk of the scenarios ``names`` (default: all)."""
    return {
        path.relative_to(SNAPSHOTS).as_posix(): path.read_bytes()
        for name in names or list(SCENARIOS)
        for path in sorted((SNAPSHOTS / name).rglob("*"))
        if path.is_file()
    }


def update(names: list[str] | None = None) -> None:
    for name in names or list(SCENARIOS):
        shutil.rmtree(SNAPSHOTS / name, ignore_errors=True)
    for key, data in produce(names).items():
        path = SNAPSHOTS / key
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)


def cli_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.snapshots", description=__doc__.split("\n")[0])
    parser.add_argument("--update", action="store_true", help="rewrite the stored snapshots from today's outputs")
    parser.add_argument("scenario", nargs="*", help=f"scenarios (default: all of {', '.join(SCENARIOS)})")
    args = parser.parse_args(argv)
    if args.update:
        update(args.scenario or None)
        return 0
    produced, kept = produce(args.scenario or None), stored(args.scenario or None)
    differ = sorted(k for k in produced.keys() | kept.keys() if produced.get(k) != kept.get(k))
    print("\n".join(differ) or "snapshots equal")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(cli_main())
