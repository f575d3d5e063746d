"""The figure of a position model: the error against the axis position, and the residual (``position.png``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from groupfit.io import save_figure
from groupfit.model import ModelFile
from groupfit.position import PositionRun

STATES_SHOWN = 4
"""Check runs whose fitted error curve over the travel is drawn (first, last and evenly between)."""


def plot_position(model: ModelFile, prun: PositionRun, path: str | Path, *, title: str = "") -> None:
    """Measured error against position, coloured by the time of the check run, with the model's curve E(P, T)
    at a few check runs' thermal states; below, the residual of every row against position."""
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.4]})
    hours = prun.run.time[prun.check] / 3600.0
    dots = top.scatter(prun.position, prun.error, c=hours, s=9, cmap="viridis", label="measured (check runs)")
    fig.colorbar(dots, ax=top, label="time of the check run (h)")
    n_checks = prun.run.n_samples
    serving = model.serving_groups(n_checks)
    low, high = prun.travel
    grid = np.linspace(low, high, 200)
    colours = dots.cmap(dots.norm(prun.run.time / 3600.0))
    for k, c in enumerate(np.unique(np.linspace(0, n_checks - 1, STATES_SHOWN).round().astype(int))):
        inputs = np.repeat(prun.run.temps[c : c + 1], len(grid), axis=0)
        curve = model.predict_position(inputs, grid, np.full(len(grid), serving[c]))
        top.plot(grid, curve, color=colours[c], lw=1.6, label="model E(P, T) at check runs shown" if k == 0 else None)
    top.set_ylabel("thermal error (µm)")
    top.set_title(title or f"{prun.run.name}: error against position, order {model.position.order}")
    top.legend(loc="best", fontsize=8)
    residual = prun.error - model.predict_position(prun.inputs(), prun.position, serving[prun.check])
    bottom.scatter(prun.position, residual, c=hours, s=7, cmap="viridis")
    bottom.axhline(0.0, color="black", lw=0.8)
    bottom.set_ylabel("residual (µm)")
    bottom.set_xlabel(f"{prun.column} (mm)")
    save_figure(fig, path, dpi=120)


__all__ = ["plot_position"]
