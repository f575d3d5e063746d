"""Runs saved by MATLAB or Octave, and binary files that are no table, as `--data` reads them."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import scipy.io
from support import same_run
from test_messy_rows import fitted_coefficients

from groupfit.data import load_run
from groupfit.errors import InputError

TEMPS = ["T1", "T2", "T3", "T4"]


def save_vectors(path, frame: pd.DataFrame, *, column_vectors: bool = False) -> None:
    shape = (-1, 1) if column_vectors else (-1,)
    scipy.io.savemat(path, {name: frame[name].to_numpy().reshape(shape) for name in frame.columns})


@pytest.mark.parametrize("column_vectors", [False, True])
def test_a_run_saved_as_matlab_vectors_is_the_plain_run(tmp_path, synthetic, column_vectors):
    frame, plain = synthetic
    path = tmp_path / "run.mat"
    save_vectors(path, frame, column_vectors=column_vectors)
    run = load_run(path, temps=TEMPS)
    same_run(run, plain)


def test_a_run_saved_as_one_struct_of_vectors_is_the_plain_run(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "run.mat"
    scipy.io.savemat(path, {"run": {name: frame[name].to_numpy() for name in frame.columns}, "gain": 2.0})
    run = load_run(path, temps=TEMPS)
    same_run(run, plain)


def test_a_matlab_run_with_datenums_and_a_constant_beside_it_fits_the_model_of_the_plain_run(tmp_path, synthetic):
    frame, _ = synthetic
    datenum = 740042.0 + 1 / 3 + (frame["time_s"] - frame["time_s"][0]) / 86400.0  # 2026-03-02 08:00
    path = tmp_path / "run.mat"
    save_vectors(path, frame.drop(columns="time_s").assign(time=datenum))
    saved = {k: v for k, v in scipy.io.loadmat(path).items() if not k.startswith("__")}
    scipy.io.savemat(path, {**saved, "gain": 2.5, "label": "spindle test"})
    run = load_run(path, temps=TEMPS, time_is_default=True)
    assert any("holds MATLAB datenums (days since the year 0)" in note for note in run.notes)
    np.testing.assert_allclose(run.time - run.time[0], frame["time_s"] - frame["time_s"][0], atol=1e-4)
    plain_csv = tmp_path / "plain.csv"
    frame.to_csv(plain_csv, index=False)
    plain_fit, mat_fit = fitted_coefficients(tmp_path, plain_csv, path)
    np.testing.assert_allclose(mat_fit, plain_fit, rtol=1e-6)


def test_mat_files_groupfit_cannot_read_are_refused_saying_how_to_save_the_run(tmp_path, synthetic):
    frame, _ = synthetic
    matrix = tmp_path / "matrix.mat"
    scipy.io.savemat(matrix, {"data": frame.to_numpy()})
    with pytest.raises(InputError, match=r"matrix.mat: holds a matrix without column names, 'data' \(300×7\).*-v7"):
        load_run(matrix, temps=TEMPS)
    hdf5 = tmp_path / "v73.mat"
    hdf5.write_bytes(b"MATLAB 7.3 MAT-file".ljust(512, b" ") + b"\x89HDF\r\n\x1a\n" + bytes(200))
    with pytest.raises(InputError, match=r"v73.mat: not a readable MAT file of version 7.3 \(.*\); save the run"):
        load_run(hdf5, temps=TEMPS)
    broken = tmp_path / "broken.mat"
    broken.write_bytes(b"not a mat file at all")
    with pytest.raises(InputError, match=r"broken.mat: not a readable MAT file"):
        load_run(broken, temps=TEMPS)


@pytest.mark.parametrize("suffix", [".csv", ".dat"])
def test_binary_data_under_any_name_is_refused_as_no_text_table(tmp_path, suffix):
    path = tmp_path / f"log{suffix}"
    rng = np.random.default_rng(1)
    path.write_bytes(b"TDSm\x04\x00\x00\x00" + rng.integers(0, 256, 4000, dtype=np.uint8).tobytes())
    with pytest.raises(InputError, match=rf"log{suffix}: binary data, not a text table"):
        load_run(path)
