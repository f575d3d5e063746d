"""Runs saved by MATLAB as version 7.3 (HDF5, ``-v7.3``): read as a run saved in the older format is read.

The files are written by hdf5storage, a library that writes MATLAB's 7.3 layout (a peer of the reader, not
groupfit's own writer); a MATLAB ``table`` object, which hdf5storage does not write, is laid out by hand as
MATLAB stores one.
"""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest
from support import same_run
from test_messy_rows import fitted_coefficients

from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.matfile import read_mat

h5py = pytest.importorskip("h5py")
hdf5storage = pytest.importorskip("hdf5storage")

TEMPS = ["T1", "T2", "T3", "T4"]


def save_73(path, variables: dict) -> None:
    hdf5storage.savemat(str(path), variables, format="7.3", matlab_compatible=True)


@pytest.mark.parametrize("column_vectors", [False, True])
def test_a_run_saved_as_version_73_vectors_is_the_plain_run(tmp_path, synthetic, column_vectors):
    frame, plain = synthetic
    shape = (-1, 1) if column_vectors else (1, -1)
    path = tmp_path / "run.mat"
    save_73(path, {name: frame[name].to_numpy().reshape(shape) for name in frame.columns})
    with open(path, "rb") as handle:
        assert handle.read(19) == b"MATLAB 7.3 MAT-file"
    same_run(load_run(path, temps=TEMPS), plain)


def test_a_version_73_struct_of_vectors_beside_a_scalar_and_text_is_the_plain_run(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "run.mat"
    run = {name: frame[name].to_numpy() for name in frame.columns}
    save_73(path, {"run": run, "gain": np.float64(2.0), "label": "spindle test"})
    same_run(load_run(path, temps=TEMPS), plain)


def test_version_73_columns_come_in_the_order_of_their_names_numbers_by_value(tmp_path):
    names = [f"T{k}" for k in (10, 2, 1, 12, 11, 3)] + ["time_s"]
    values = {name: np.arange(4.0) + j for j, name in enumerate(names)}
    path = tmp_path / "run.mat"
    save_73(path, values)
    frame = read_mat(path, "run.mat")
    assert list(frame.columns) == ["T1", "T2", "T3", "T10", "T11", "T12", "time_s"]
    for name in names:
        np.testing.assert_array_equal(frame[name], values[name])


def test_a_version_73_run_fits_the_model_of_the_same_run_saved_as_csv(tmp_path, synthetic):
    frame, _ = synthetic
    path = tmp_path / "run.mat"
    save_73(path, {name: frame[name].to_numpy().reshape(-1, 1) for name in frame.columns})
    plain_csv = tmp_path / "plain.csv"
    frame.to_csv(plain_csv, index=False)
    plain_fit, mat_fit = fitted_coefficients(tmp_path, plain_csv, path)
    np.testing.assert_allclose(mat_fit, plain_fit, rtol=1e-9)


def table_object_file(path) -> None:
    """A MATLAB ``table`` as MATLAB saves it with -v7.3: an opaque uint32 dataset of class 'table'."""
    with h5py.File(path, "w", userblock_size=512) as file:
        data = file.create_dataset("readings", data=np.array([[3707764736, 2, 1, 1, 1, 1]], dtype=np.uint32))
        data.attrs["MATLAB_class"] = np.bytes_(b"table")
        data.attrs["MATLAB_object_decode"] = np.int32(3)
        file.create_group("#subsystem#")
    with open(path, "r+b") as handle:
        handle.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116, b" "))


def test_version_73_files_groupfit_cannot_read_are_refused_saying_how_to_save_the_run(tmp_path, synthetic):
    frame, _ = synthetic
    matrix = tmp_path / "matrix.mat"
    save_73(matrix, {"data": frame.to_numpy()})
    with pytest.raises(InputError, match=r"matrix.mat: holds a matrix without column names, 'data' \(300×7\).*-v7"):
        load_run(matrix, temps=TEMPS)
    table = tmp_path / "table.mat"
    table_object_file(table)
    with pytest.raises(InputError, match=r"table.mat: holds no vectors of numbers \(a MATLAB table or timetable"):
        load_run(table, temps=TEMPS)


def test_without_h5py_a_version_73_file_is_refused_naming_the_package(tmp_path, synthetic, monkeypatch):
    frame, _ = synthetic
    path = tmp_path / "run.mat"
    save_73(path, {name: frame[name].to_numpy() for name in frame.columns})
    monkeypatch.setitem(sys.modules, "h5py", None)  # import h5py raises ImportError
    with pytest.raises(InputError, match=r'run.mat: a MAT file of version 7.3 \(HDF5\): .*h5py.*"groupfit\[mat73\]"'):
        load_run(path, temps=TEMPS)


def test_a_version_73_file_and_a_version_7_file_of_one_run_give_the_same_table(tmp_path, synthetic):
    import scipy.io

    frame, _ = synthetic
    v7, v73 = tmp_path / "v7.mat", tmp_path / "v73.mat"
    variables = {name: frame[name].to_numpy().reshape(-1, 1) for name in ["T1", "T2", "T3", "T4", "error_um"]}
    scipy.io.savemat(v7, variables)
    save_73(v73, variables)
    pd.testing.assert_frame_equal(read_mat(v73, "v73.mat"), read_mat(v7, "v7.mat"))
