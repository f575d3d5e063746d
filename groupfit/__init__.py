"""groupfit: grouped regression models for machine-tool thermal-error compensation."""

__version__ = "0.1.0"
