"""The ball-screw temperature-field model of seed 003 (Li et al., Opt. Precision Eng. 2012).

* :mod:`.model` — the analytic temperature rise Γ(x, t) and thermal error E(x, t),
  and the :class:`BallScrewModel` estimator;
* :mod:`.identify` — the paper's identification: h and (C1, C2) from the steady
  profile, α′(t) from the transient and α′(τ0) by a linear fit, C1 and C2 of a
  new source from the first t_r seconds of two sensors;
* :mod:`.runs` — reading a screw run (sensor positions from the column names);
* :mod:`.modelfile` — the model file of kind ``ballscrew``;
* :mod:`.compare` — the screw model against an MLR on the same sensors;
* :mod:`.plots` — figures.

See ``docs/ballscrew.md``.
"""

from .model import BallScrewModel
from .physics import temperature_rise, thermal_error

__all__ = ["BallScrewModel", "temperature_rise", "thermal_error"]
