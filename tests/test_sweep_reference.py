"""A sweep takes the inputs as fit and compare default to: rises over T_amb when the run has that column
(kept for every grid point, also where fit would drop it by the next-run estimate)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.data import load_run
from groupfit.models.grouped import GroupedRegressor
from groupfit.sweep.config import read_study
from groupfit.sweep.runs import execute_run

DATA = Path(__file__).resolve().parents[1] / "datasets" / "paper_cycle.csv"


def test_sweep_fits_rises_over_the_ambient_like_fit(tmp_path):
    frame = pd.read_csv(DATA).iloc[:240]
    frame["T_amb"] += np.linspace(0.0, 2.0, len(frame))  # a drifting ambient: absolute and rise fits differ
    data = tmp_path / "run.csv"
    frame.to_csv(data, index=False)
    config = tmp_path / "study.toml"
    config.write_text(f'[data]\npath = "{data.as_posix()}"\n[grid]\np = [1]\nsearch = "exact"\n', encoding="utf-8")
    (run,) = read_study(config).runs
    result = execute_run(run.spec, run.path)
    assert result["status"] == "done", result["error"]
    assert result["reference"] == "T_amb"
    sensors = result["sensors"]
    rises = load_run(data, temps=sensors).temps - frame[["T_amb"]].to_numpy()
    model = run.spec["model"]
    direct = GroupedRegressor(p=1, n=model["n"], c=model["c"], objective=model["objective"], search="exact")
    direct.fit(rises, frame["error_um"].to_numpy())
    assert result["breaks"] == direct.breaks_
    np.testing.assert_allclose(result["coefficients"], np.column_stack([direct.intercept_, direct.coef_]), rtol=1e-9)
    absolute = GroupedRegressor(p=1, n=model["n"], c=model["c"], objective=model["objective"], search="exact")
    absolute.fit(rises + frame[["T_amb"]].to_numpy(), frame["error_um"].to_numpy())
    assert result["objective"] != pytest.approx(absolute.objective_value_, rel=1e-6)
