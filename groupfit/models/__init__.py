"""Thermal-error models in the scikit-learn style.

The estimators are loaded when first named (``groupfit.models.GroupedRegressor``),
so that the low layers can use :mod:`groupfit.models.ridge` without loading
the searches.
"""

from importlib import import_module

_HOMES = {
    "AR1Model": "groupfit.models.ar1",
    "GroupedRegressor": "groupfit.models.grouped",
    "MLR": "groupfit.models.mlr",
}

__all__ = sorted(_HOMES)


def __getattr__(name: str):
    if name not in _HOMES:
        raise AttributeError(f"module 'groupfit.models' has no attribute {name!r}")
    return getattr(import_module(_HOMES[name]), name)
