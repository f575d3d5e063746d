"""A file whose clock starts again is told by its first row to be the rest of the modelling recording."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.pickup import LOCAL_MARGIN, LOCAL_ROWS, distance, last_readings, pickup_limit, reading_steps

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
TEMPS = ["T1", "T2", "T3", "T4"]
CUT = 330


def cli(*args) -> int:
    return main([str(a) for a in args])


def restarted(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with its clock started again at 0, as a logger that starts every file's clock does."""
    out = frame.reset_index(drop=True).copy()
    out["time_s"] -= out["time_s"].iloc[0]
    return out


def replayed(folder: Path, data: Path, *args) -> dict:
    out = folder / "replay.json"
    assert cli("replay", folder / "model.json", "--data", data, *args, "--json", out) == 0
    return json.loads(out.read_text())


@pytest.fixture(scope="module")
def cut(tmp_path_factory):
    """The paper cycle cut at row CUT; the rest with its own clock, with its clock after a pause, and a new
    day's run (another seed of the same cycle); the model fitted on the first part."""
    folder = tmp_path_factory.mktemp("pickup")
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    whole.to_csv(folder / "whole.csv", index=False)
    whole.iloc[:CUT].to_csv(folder / "first.csv", index=False)
    restarted(whole.iloc[CUT:]).to_csv(folder / "rest.csv", index=False)
    restarted(whole.iloc[CUT + 30 :]).to_csv(folder / "paused.csv", index=False)  # logging stopped for 30 rows
    restarted(whole).to_csv(folder / "next_day.csv", index=False)  # a cold start: the same programme again
    assert cli("fit", "--data", folder / "first.csv", "--p", "2", "--temps", ",".join(TEMPS), "--out", folder) == 0
    return folder


def test_the_distance_and_its_limit_are_the_rows_differences_in_units_of_their_median_change():
    rng = np.random.default_rng(3)
    frame = pd.DataFrame({"time_s": np.arange(200.0) * 10, "error_um": np.cumsum(rng.normal(size=200))})
    frame["T1"] = 20 + np.cumsum(rng.normal(scale=0.05, size=200))
    frame["T2"] = np.round(21 + np.cumsum(rng.normal(scale=0.02, size=200)), 1)  # a sensor of 0.1 °C steps
    frame.loc[170, "T1"] = np.nan
    run = load_run(frame, temps=["T1", "T2"], allow_nonfinite=True)
    steps = reading_steps(run)
    brute = {}
    for column in ("T1", "T2", "error_um"):
        change = [abs(b - a) for a, b in zip(frame[column], frame[column][1:]) if np.isfinite(b - a)]
        brute[column] = float(np.median(change)) or float(np.mean(change))
    assert steps == pytest.approx(brute, rel=1e-12)
    rows = []
    for k in range(200 - LOCAL_ROWS, 200):
        terms = [
            abs(frame[c][k] - frame[c][k - 1]) / brute[c]
            for c in ("T1", "T2", "error_um")
            if np.isfinite(frame[c][k] - frame[c][k - 1])
        ]
        rows.append(sum(terms) / len(terms))
    assert pickup_limit(run, steps) == pytest.approx(LOCAL_MARGIN * max(rows), rel=1e-12)
    last = last_readings(run)
    assert last == {c: float(frame[c].iloc[-1]) for c in ("T1", "T2", "error_um")}
    first = {"T1": last["T1"] + 2 * brute["T1"], "T2": last["T2"], "error_um": last["error_um"] - brute["error_um"]}
    assert distance(first, last, steps) == pytest.approx(1.0)
    assert distance({"T1": last["T1"]}, last, {**steps, "T1": 0.0}) == 0.0
    assert distance({"T1": last["T1"] + 0.1}, last, {**steps, "T1": 0.0}) == np.inf  # a column that never changed


def test_a_rest_on_its_own_clock_is_replayed_after_the_modelling_file_as_the_whole_recording(cut, capsys):
    capsys.readouterr()
    rest = replayed(cut, cut / "rest.csv")
    assert "its first row picks up where the modelling recording" in capsys.readouterr().out
    (recording,) = json.loads((cut / "model.json").read_text())["training"]["recordings"]
    assert rest["continues"] == [recording["path"]] and rest["history_samples"] == CUT
    whole = replayed(cut, cut / "whole.csv")["samples"][CUT:]
    np.testing.assert_allclose([s["prediction_um"] for s in rest["samples"]], [s["prediction_um"] for s in whole])
    assert [s["group"] for s in rest["samples"]] == [s["group"] for s in whole]
    fresh = replayed(cut, cut / "rest.csv", "--fresh")
    assert fresh["continues"] == [] and fresh["samples"][0]["group"] == 1 < rest["samples"][0]["group"]


@pytest.mark.parametrize("other", ["paused.csv", "next_day.csv", "first.csv"])
def test_a_pause_a_new_day_or_the_modelling_file_itself_starts_afresh(cut, other, capsys):
    capsys.readouterr()
    result = replayed(cut, cut / other)
    assert result["continues"] == [] and result["history_samples"] == 0
    assert "picks up" not in capsys.readouterr().out


def test_a_model_file_without_the_last_row_tells_a_continuation_by_its_clock_alone(cut, tmp_path):
    model = json.loads((cut / "model.json").read_text())
    for key in ("last_readings", "reading_steps", "pickup_limit"):
        del model["training"]["recordings"][0][key]
    (tmp_path / "model.json").write_text(json.dumps(model))
    assert replayed(tmp_path, cut / "rest.csv")["continues"] == []


def test_two_dated_files_are_told_by_their_dates_whatever_their_readings(tmp_path):
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    start = pd.Timestamp("2026-03-01 08:00:00")
    for name, part, shift_s in (("first", whole.iloc[:CUT], 0.0), ("rest", whole.iloc[CUT:], 3600.0)):
        out = part.copy()
        stamps = start + pd.to_timedelta(out.pop("time_s") + shift_s, unit="s")
        out.insert(0, "Timestamp", stamps.dt.strftime("%Y-%m-%d %H:%M:%S"))
        out.to_csv(tmp_path / f"{name}.csv", index=False)
    assert cli("fit", "--data", tmp_path / "first.csv", "--p", "0", "--temps", ",".join(TEMPS), "--out", tmp_path) == 0
    assert replayed(tmp_path, tmp_path / "rest.csv")["continues"] == []  # an hour later by its dates


@pytest.mark.parametrize(
    ("key", "value"), [("last_readings", {"T1": "warm"}), ("reading_steps", {"T1": -1.0}), ("pickup_limit", None)]
)
def test_a_model_file_with_a_bad_last_row_is_refused(cut, tmp_path, key, value):
    model = json.loads((cut / "model.json").read_text())
    model["training"]["recordings"][0][key] = value
    (tmp_path / "bad.json").write_text(json.dumps(model))
    with pytest.raises(InputError, match=rf"training.recordings\[0\].{key} must"):
        ModelFile.load(tmp_path / "bad.json")


@pytest.mark.skipif(not SHARED.is_file(), reason="the shared measured test is not here")
def test_the_measured_tests_rest_on_its_own_clock_is_replayed_with_checks_as_the_continuing_log(tmp_path):
    measured = pd.read_csv(SHARED)
    at = int(0.6 * len(measured))
    measured.iloc[:at].to_csv(tmp_path / "first.csv", index=False)
    measured.iloc[at:].to_csv(tmp_path / "rest.csv", index=False)
    restarted(measured.iloc[at:]).to_csv(tmp_path / "rest_own_clock.csv", index=False)
    fit = ("fit", "--data", tmp_path / "first.csv", "--error", "disp_ch3_um", "--p", "0", "--out", tmp_path)
    assert cli(*fit, "--quiet") == 0
    checks = ("--probe-every", "1800")
    as_logged = replayed(tmp_path, tmp_path / "rest.csv", *checks)
    own_clock = replayed(tmp_path, tmp_path / "rest_own_clock.csv", *checks)
    assert own_clock["history_samples"] == as_logged["history_samples"] == at
    assert [s["residual_um"] for s in own_clock["samples"]] == [s["residual_um"] for s in as_logged["samples"]]
    assert own_clock["rms_um"] < replayed(tmp_path, tmp_path / "rest_own_clock.csv", *checks, "--fresh")["rms_um"]
