"""Figures of compare: R against p keeps its legend off the data and marks whole p; the pseudo-hysteresis figure."""

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

import groupfit.plots as plots


def captured(monkeypatch):
    figures = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, path, **options: figures.append(fig))
    return figures


def test_r_against_p_legend_outside_the_axes_and_integer_ticks(monkeypatch, tmp_path):
    figures = captured(monkeypatch)
    rows = [{"run": "a", "model": "grouped", "p": p, "R_um": 100.0 / (p + 1)} for p in range(1, 5)]
    rows += [{"run": "a", "model": "mlr", "p": 0, "R_um": 120.0}, {"run": "a", "model": "ar1", "p": None, "R_um": 90.0}]
    plots.plot_r_against_p([110.0, 50.0, 30.0, 25.0, 22.0], rows, ["a"], tmp_path / "r.png")
    (fig,) = figures
    axis = fig.axes[0]
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    legend = axis.get_legend().get_window_extent(renderer)
    assert legend.x0 >= axis.get_window_extent(renderer).x1  # right of the plotting area, over no data
    assert list(axis.get_xticks()) == [0, 1, 2, 3, 4]


def test_heating_phases_follow_the_sign_of_the_slope():
    t = np.arange(400)
    error = np.where(t < 200, t, 400 - t).astype(float)  # up, then down
    rising = plots.heating_phases(error, window=3)
    assert rising[:197].all() and not rising[203:].any()


def test_hysteresis_figure_has_one_panel_per_input(monkeypatch, tmp_path):
    figures = captured(monkeypatch)
    t = np.linspace(0, 1, 300)
    temps = np.column_stack([np.sin(np.pi * t), np.sin(np.pi * t - 0.3), t])
    plots.plot_hysteresis(temps, ["T1", "T2", "T3"], np.sin(np.pi * t - 0.15), tmp_path / "h.png")
    (fig,) = figures
    visible = [axis for axis in fig.axes if axis.get_visible()]
    assert [axis.get_xlabel() for axis in visible] == ["T1", "T2", "T3"]
