"""Thermal-error models in the scikit-learn style."""

from groupfit.models.grouped import GroupedRegressor
from groupfit.models.mlr import MLR

__all__ = ["GroupedRegressor", "MLR"]
