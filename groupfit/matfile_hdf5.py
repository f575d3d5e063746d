"""The variables of a MAT file of version 7.3 (``save run.mat time_s T1 T2 error_um -v7.3``), MATLAB's HDF5 layout.

MATLAB keeps every variable as an HDF5 dataset at the file's root, its class
in the attribute ``MATLAB_class`` and its dimensions in reverse (a column
vector of N rows is a dataset of shape 1 × N); a struct is a group whose
datasets are its fields, in the order of its ``MATLAB_fields``. A variable of
numbers comes back as SciPy's ``loadmat(…, squeeze_me=True)`` gives one of an
older file: a vector as one dimension, a matrix as rows × columns, a struct as
a dict of its fields; anything else (text, cells, sparse or complex
matrices, MATLAB objects such as a ``table``) as None. The variables come in
the order they were saved where the file keeps it, else in the order of their
names, numbers by value (``T2`` before ``T10``). Reading needs the package
h5py (``pip install "groupfit[mat73]"``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

NUMBER_CLASSES = frozenset(
    {"double", "single", "logical", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
)


def read_hdf5_variables(path: Path) -> dict[str, np.ndarray | dict | None]:
    """Every variable of the file by name (module docstring). Raises ImportError without h5py and OSError when
    the file is no readable HDF5 file."""
    import h5py  # an optional dependency: ImportError tells the reader to install it

    with h5py.File(path, "r") as file:
        names = [name for name in file.keys() if not name.startswith("#")]  # '#refs#', '#subsystem#'
        if not file.id.get_create_plist().get_link_creation_order():
            names.sort(key=_natural_key)
        return {name: _value(file[name], h5py) for name in names}


def _value(item, h5py) -> np.ndarray | dict | None:
    matlab_class = _text(item.attrs.get("MATLAB_class", b""))
    if isinstance(item, h5py.Group):
        if matlab_class != "struct":
            return None
        fields = [_text(field) for field in item.attrs.get("MATLAB_fields", [])] or list(item.keys())
        return {name: _value(item[name], h5py) for name in fields if name in item}
    if (
        matlab_class not in NUMBER_CLASSES
        or item.attrs.get("MATLAB_empty", 0)
        or "MATLAB_sparse" in item.attrs
        or item.dtype.kind not in "biuf"  # a complex matrix is a compound of real and imaginary parts
    ):
        return None
    return np.squeeze(np.asarray(item[()]).T)


def _text(value) -> str:
    """An attribute's text: bytes, or an array of single characters (how MATLAB lists a struct's fields)."""
    if isinstance(value, np.ndarray):
        return b"".join(np.atleast_1d(value).tolist()).decode("utf-8", "replace")
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def _natural_key(name: str) -> list[tuple[int, int | str]]:
    return [(0, int(part)) if part.isdigit() else (1, part) for part in re.split(r"(\d+)", name) if part]


__all__ = ["read_hdf5_variables"]
