"""A run saved by MATLAB or Octave (``save run.mat time T1 T2 error``): its vectors as the columns of a table.

A MAT file of version 4, 5 or 7 (MATLAB's default) is read with SciPy, one
of version 7.3 (HDF5, ``-v7.3``) with h5py (:mod:`groupfit.matfile_hdf5`, an
optional dependency); each variable that is a vector of numbers becomes a
column named as the variable, in the file's order, and the vectors of the
most common length make the run (or the fields of the one struct that holds
vectors: ``run.time_s``, ``run.T1``). A matrix without column names and a
MATLAB ``table`` or ``timetable`` object (which only MATLAB reads) are
refused, each saying how to save the run so that it is read.
"""

from __future__ import annotations

import zlib
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.io
from scipy.io.matlab import MatReadError

from groupfit.errors import InputError, first_line
from groupfit.matfile_hdf5 import read_hdf5_variables

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
EXPORT = "save the run as separate vectors (save('run.mat', 'time_s', 'T1', …, '-v7')) or as CSV (writetable)"


def read_mat(path: Path, label: str) -> pd.DataFrame:
    """The vectors of a MAT file as a table (module docstring); refused in one line when it holds none."""
    with open(path, "rb") as handle:
        head = handle.read(1024)
    if HDF5_SIGNATURE in head:
        variables = _version_73(path, label)
    else:
        try:
            variables = scipy.io.loadmat(path, squeeze_me=True, chars_as_strings=True)
        except (MatReadError, ValueError, TypeError, IndexError, KeyError, EOFError, OSError, zlib.error) as exc:
            raise InputError(f"{label}: not a readable MAT file ({first_line(exc)}); {EXPORT}") from None
    variables = {name: value for name, value in variables.items() if not name.startswith("__")}
    vectors, matrices = _vectors(variables)
    if not vectors:  # one struct of vectors (run.time_s, run.T1 …) is the run
        found = [found for found in (_vectors(_fields(value))[0] for value in variables.values()) if found]
        vectors = found[0] if len(found) == 1 else {}
    lengths = Counter(len(v) for v in vectors.values())
    if not lengths or max(lengths.values()) < 2:
        held = f"a matrix without column names, {matrices[0]}" if matrices else "no vectors of numbers"
        raise InputError(f"{label}: holds {held} (a MATLAB table or timetable is read only by MATLAB); {EXPORT}")
    length = max(lengths, key=lambda n: (lengths[n], n))
    return pd.DataFrame({name: v for name, v in vectors.items() if len(v) == length})


def _version_73(path: Path, label: str) -> dict:
    try:
        return read_hdf5_variables(path)
    except ImportError:
        raise InputError(
            f"{label}: a MAT file of version 7.3 (HDF5): reading it needs the package h5py (pip install h5py, or "
            f'"groupfit[mat73]"); or {EXPORT}'
        ) from None
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise InputError(f"{label}: not a readable MAT file of version 7.3 ({first_line(exc)}); {EXPORT}") from None


def _vectors(variables: dict) -> tuple[dict[str, np.ndarray], list[str]]:
    """The vectors of numbers among ``variables`` (as float), and the matrices of numbers, described."""
    vectors, matrices = {}, []
    for name, value in variables.items():
        if not isinstance(value, np.ndarray) or value.dtype.kind not in "biuf":
            continue
        if value.ndim == 1 and value.size > 1:
            vectors[name] = value.astype(float)
        elif value.ndim == 2:
            matrices.append(f"'{name}' ({value.shape[0]}×{value.shape[1]})")
    return vectors, matrices


def _fields(value) -> dict:
    """The fields of a MATLAB struct of one element (empty: not one)."""
    if isinstance(value, dict):
        return value
    names = getattr(getattr(value, "dtype", None), "names", None)
    if not names or getattr(value, "size", 0) != 1:
        return {}
    record = value.reshape(-1)[0]
    return {name: record[name] for name in names}


__all__ = ["read_mat"]
