"""Thermal-error models in the scikit-learn style."""

from groupfit.models.ar1 import AR1Model
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.mlr import MLR

__all__ = ["AR1Model", "GroupedRegressor", "MLR"]
