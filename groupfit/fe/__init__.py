"""Finite-element data generator (scikit-fem).

Three scenarios, chosen by the config's ``kind``:

* ``"headstock"`` — a turning-centre headstock housing, transient heat
  conduction and linear thermo-elasticity; the radial thermal error of the
  spindle axis at the nose under a duty schedule (:mod:`.headstock`);
* ``"rod"`` — the 1-D spindle rod of the physics AR(1) model (:mod:`.rod`);
* ``"ballscrew"`` — a feed-axis ball screw heated by a fixed source or a
  moving nut (:mod:`.ballscrew`, ``docs/ballscrew.md``).

See ``docs/fe_model.md`` for the model, its boundaries and its verification.
"""

from __future__ import annotations

import pandas as pd

from groupfit.plots import plot_dataset

from .ballscrew import BallScrewScenario, simulate_ballscrew
from .config import HeadstockScenario, RodScenario, parse_config
from .headstock import simulate_headstock
from .rod import simulate_rod

__all__ = ["simulate_config", "plot_dataset", "parse_config"]


def simulate_config(config: dict, *, progress: bool = True) -> pd.DataFrame:
    """Simulate the scenario described by a parsed TOML config.

    Parameters
    ----------
    config
        The scenario table, with ``kind = "headstock"``, ``"rod"`` or ``"ballscrew"``.
    progress
        Show a progress bar.

    Returns
    -------
    pandas.DataFrame
        The data set: ``time_s`` first (uniform, from 0), then temperatures
        (°C), ``error_um`` and the condition columns.

    Raises
    ------
    groupfit.errors.InputError
        When the config has an unknown key, a wrong type or an invalid value.
    """
    scenario = parse_config(config)
    if isinstance(scenario, BallScrewScenario):
        return simulate_ballscrew(scenario, progress=progress)
    if isinstance(scenario, RodScenario):
        return simulate_rod(scenario, progress=progress)
    assert isinstance(scenario, HeadstockScenario)
    return simulate_headstock(scenario, progress=progress)
