"""Figures of the ball-screw model (``matplotlib.figure.Figure``, written as PNG)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from groupfit.io import save_figure

from .runs import sensor_positions

CONDITION_COLUMNS = ("time_s", "error_um", "probe_x_m", "power_W", "nut_x_m", "screw_rpm", "T_amb")


def plot_screw_dataset(frame, path: str | Path, title: str = "") -> None:
    """Sensor temperatures (top) and the thermal error at the probe (bottom) of a screw data set."""
    hours = frame["time_s"].to_numpy(dtype=float) / 3600.0
    fig = Figure(figsize=(8, 6), constrained_layout=True)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for column in sensor_positions(frame.columns):
        top.plot(hours, frame[column], lw=1.0, label=column)
    top.set_ylabel("temperature (°C)")
    top.legend(ncol=4, fontsize="small")
    top.set_title(title)
    if "error_um" in frame:
        bottom.plot(hours, frame["error_um"], color="k", lw=0.8)
    bottom.set_ylabel("thermal error at the probe (µm)")
    bottom.set_xlabel("time (h)")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
    save_figure(fig, Path(path), dpi=110)


def plot_rises(time_s, positions, measured, predicted, path: str | Path, title: str = "") -> None:
    """Measured vs predicted rises at the given positions (left) and their difference (right),
    the layout of the paper's Fig. 5."""
    hours = np.asarray(time_s, dtype=float) / 3600.0
    fig = Figure(figsize=(11, 4.5), constrained_layout=True)
    left, right = fig.subplots(1, 2)
    for j, x in enumerate(positions):
        line = left.plot(hours, measured[:, j], lw=1.0, label=f"{100 * x:g} cm measured")[0]
        left.plot(hours, predicted[:, j], lw=1.2, ls="--", color=line.get_color(), label=f"{100 * x:g} cm model")
        right.plot(hours, predicted[:, j] - measured[:, j], lw=0.9, color=line.get_color(), label=f"{100 * x:g} cm")
    left.set_ylabel("temperature rise (K)")
    right.set_ylabel("model − measured (K)")
    right.axhline(0.0, color="k", lw=0.6)
    left.legend(fontsize="x-small", ncol=2)
    right.legend(fontsize="x-small")
    for axis in (left, right):
        axis.set_xlabel("time (h)")
        axis.grid(alpha=0.3)
    fig.suptitle(title)
    save_figure(fig, Path(path), dpi=110)


def plot_error(time_s, measured, predictions: dict, path: str | Path, title: str = "") -> None:
    """Measured thermal error at the probe vs the models' (top) and residuals (bottom), as the paper's Fig. 6."""
    hours = np.asarray(time_s, dtype=float) / 3600.0
    fig = Figure(figsize=(9, 6), constrained_layout=True)
    top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.5]})
    top.plot(hours, measured, color="k", lw=1.2, label="measured (FE)")
    styles = iter([("tab:red", "--"), ("tab:green", "-."), ("tab:blue", ":")])
    for label, values in predictions.items():
        color, ls = next(styles)
        top.plot(hours, values, color=color, ls=ls, lw=1.3, label=label)
        bottom.plot(hours, np.asarray(values) - measured, color=color, ls=ls, lw=1.0, label=label)
    top.set_ylabel("thermal error (µm)")
    top.legend(fontsize="small")
    top.set_title(title)
    bottom.axhline(0.0, color="k", lw=0.6)
    bottom.set_ylabel("model − measured (µm)")
    bottom.set_xlabel("time (h)")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
    save_figure(fig, Path(path), dpi=110)
