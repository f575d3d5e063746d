"""``groupfit iso230``: ISO 230-2 evaluation of bidirectional positioning runs (groupfit.iso230)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from groupfit.commands import common
from groupfit.io import save_figure
from groupfit.iso230 import DEVIATION_VALUES, STANDARD_REPEATS, TARGET_VALUES, Iso230Result, load_runs, read_in


def add_parser(verbs) -> None:
    iso = verbs.add_parser("iso230")
    iso.add_argument(
        "run", metavar="RUN", help="the runs: one row per approach (target position, direction, deviation)"
    )
    iso.add_argument("--target", default="target_mm", metavar="COLUMN", help="target position, mm (target_mm)")
    iso.add_argument(
        "--direction", default="direction", metavar="COLUMN", help="approach direction, + or - (direction)"
    )
    iso.add_argument(
        "--deviation",
        default="deviation_um",
        metavar="COLUMN",
        help="positional deviation, actual minus target, um (deviation_um)",
    )
    common.add_json_option(iso, "the evaluation")
    common.add_out_option(iso, "folder for iso230.png (the mean deviations with their ±2s bands)")
    common.add_quiet_option(iso)
    iso.set_defaults(handler=run_iso230)


def run_iso230(args: argparse.Namespace) -> int:
    out_dir = common.plan_outputs(args, args.run, folder=args.out, files=("iso230.png",))
    result = load_runs(args.run, target=args.target, direction=args.direction, deviation=args.deviation)
    data = {"run": str(args.run), **result.to_json()}
    converted = {}
    for column, plausible in ((args.target, TARGET_VALUES), (args.deviation, DEVIATION_VALUES)):
        unit, factor = read_in(column, plausible)
        if factor != 1.0:
            converted[column] = {"unit": unit, "given_in": plausible.unit}
    if converted:
        data["columns_read_in"] = converted
    written = []
    if out_dir is not None:
        figure = out_dir / "iso230.png"
        plot_iso230(result, figure, title=Path(args.run).name)
        written.append(figure)
    common.finish_outputs(args, iso230_report(data), data, written)
    return 0


def iso230_report(data: dict) -> str:
    """The table per target and the axis' parameters, as ``groupfit iso230`` prints them."""
    axis = data["axis_um"]
    lines = [
        f"ISO 230-2: {data['targets']} targets, {data['repeats']} runs each way"
        + ("" if data["standard_cycle"] else f" (the standard test cycle takes {STANDARD_REPEATS})"),
        f"{'P mm':>10} {'x↑ um':>8} {'x↓ um':>8} {'x um':>8} {'B um':>7} {'s↑':>6} {'s↓':>6} {'R↑':>6} {'R↓':>6} "
        f"{'R':>6}",
    ]
    for column, read in data.get("columns_read_in", {}).items():
        lines.insert(1, f"column   '{column}' read in {read['unit']} (by its name), given below in {read['given_in']}")
    for p in data["positions"]:
        lines.append(
            f"{p['target_mm']:10.3f} {p['mean_up_um']:8.3f} {p['mean_down_um']:8.3f} {p['mean_um']:8.3f} "
            f"{p['B_um']:7.3f} {p['s_up_um']:6.3f} {p['s_down_um']:6.3f} {p['R_up_um']:6.3f} {p['R_down_um']:6.3f} "
            f"{p['R_um']:6.3f}"
        )
    lines.append(
        f"axis     reversal B {axis['B']:.3f} (mean {axis['B_mean']:.3f}), repeatability R↑ {axis['R_up']:.3f} "
        f"R↓ {axis['R_down']:.3f} R {axis['R']:.3f}"
    )
    lines.append(
        f"         systematic E↑ {axis['E_up']:.3f} E↓ {axis['E_down']:.3f} E {axis['E']:.3f}, mean bidirectional "
        f"range M {axis['M']:.3f}, accuracy A↑ {axis['A_up']:.3f} A↓ {axis['A_down']:.3f} A {axis['A']:.3f} (um)"
    )
    return "\n".join(lines)


def plot_iso230(result: Iso230Result, path: Path, *, title: str = "") -> None:
    """The mean deviations ↑ and ↓ with their ±2s bands, the mean bidirectional deviation and every run."""
    fig = Figure(figsize=(8, 4.8), layout="constrained")
    ax = fig.subplots()
    p = result.targets_mm
    for runs, mean, s, color, word in (
        (result.up, result.mean_up, result.s_up, "tab:red", "↑"),
        (result.down, result.mean_down, result.s_down, "tab:blue", "↓"),
    ):
        ax.plot(np.tile(p, (len(runs), 1)).T, runs.T, ".", color=color, ms=3, alpha=0.5)
        ax.plot(p, mean, "-", color=color, lw=1.4, label=f"mean {word}")
        ax.fill_between(p, mean - 2 * s, mean + 2 * s, color=color, alpha=0.15, label=f"mean {word} ± 2s")
    ax.plot(p, result.mean, "--", color="black", lw=1.0, label="mean bidirectional")
    axis = result.axis()
    ax.set_title(
        f"{title}: A = {axis['A']:.2f}, B = {axis['B']:.2f}, R = {axis['R']:.2f}, E = {axis['E']:.2f}, "
        f"M = {axis['M']:.2f} µm"
    )
    ax.set_xlabel("target position (mm)")
    ax.set_ylabel("positional deviation (µm)")
    ax.legend(loc="best", fontsize=8)
    save_figure(fig, path, dpi=120)


__all__ = ["iso230_report", "plot_iso230", "run_iso230"]
