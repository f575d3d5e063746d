"""A logger that rolls its files: the next file of a recording stamped with dates is told by its date-times."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError
from groupfit.model import ModelFile

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
START = pd.Timestamp("2026-03-01 22:30:00")
CUT = 330
FORMS = {
    "day first": lambda t: t.strftime("%d.%m.%Y %H:%M:%S"),
    "ISO with offset": lambda t: t.strftime("%Y-%m-%dT%H:%M:%S") + "+01:00",
}


def dated(frame: pd.DataFrame, form, shift_s: float = 0.0) -> pd.DataFrame:
    out = frame.copy()
    stamps = START + pd.to_timedelta(out.pop("time_s") + shift_s, unit="s")
    out.insert(0, "Timestamp", [form(t) for t in stamps])
    return out


def cli(*args) -> int:
    return main([str(a) for a in args])


@pytest.fixture(scope="module", params=list(FORMS))
def rolled(request, tmp_path_factory):
    """A recording rolled into two files at row CUT (and the whole), its model fitted on the first."""
    folder = tmp_path_factory.mktemp("rolled")
    whole = pd.read_csv(DATASETS / "paper_cycle.csv")
    form = FORMS[request.param]
    dated(whole, form).to_csv(folder / "whole.csv", index=False)
    dated(whole.iloc[:CUT], form).to_csv(folder / "first.csv", index=False)
    dated(whole.iloc[CUT:], form).to_csv(folder / "rest.csv", index=False)
    dated(whole.iloc[CUT:], form, shift_s=3600.0).to_csv(folder / "an_hour_later.csv", index=False)
    numeric = whole.iloc[CUT:].copy()
    numeric.to_csv(folder / "rest_in_seconds.csv", index=False)  # its own clock, which runs on from 33000 s
    assert (
        cli("fit", "--data", folder / "first.csv", "--p", "2", "--temps", "T1,T2,T3,T4", "--out", folder, "--quiet")
        == 0
    )
    return folder, request.param


def replayed(folder: Path, *args) -> dict:
    out = folder / "replay.json"
    assert cli("replay", folder / "model.json", *args, "--json", out) == 0
    return json.loads(out.read_text())


def test_the_next_file_is_replayed_after_the_modelling_file_as_the_whole_recording(rolled, capsys):
    folder, form = rolled
    (recording,) = json.loads((folder / "model.json").read_text())["training"]["recordings"]
    offset_h = 1.0 if form == "ISO with offset" else 0.0  # the stamps' own offset, taken to UTC
    assert recording["clock_origin_s"] == (START - pd.Timedelta(hours=offset_h)).tz_localize("UTC").timestamp()
    capsys.readouterr()
    unasked = replayed(folder, "--data", folder / "rest.csv")
    assert "continues the modelling recording" in capsys.readouterr().out
    declared = replayed(folder, "--data", folder / "rest.csv", "--continues", folder / "first.csv")
    assert unasked["continues"] == [recording["path"]] and unasked["history_samples"] == CUT
    assert unasked["samples"] == declared["samples"]
    whole = replayed(folder, "--data", folder / "whole.csv")["samples"][CUT:]
    np.testing.assert_allclose(
        [s["prediction_um"] for s in unasked["samples"]], [s["prediction_um"] for s in whole], atol=1e-9
    )
    assert [s["group"] for s in unasked["samples"]] == [s["group"] for s in whole]


@pytest.mark.parametrize("other", ["an_hour_later.csv", "rest_in_seconds.csv"])
def test_a_file_whose_stamps_do_not_go_on_from_the_modelling_file_starts_afresh(rolled, other):
    folder, _ = rolled
    result = replayed(folder, "--data", folder / other)
    assert result["continues"] == [] and result["history_samples"] == 0


def test_compare_judges_a_rolled_validation_file_with_the_modelling_file_in_front(rolled, capsys):
    folder, _ = rolled
    args = ("compare", "--data", folder / "first.csv", "--validate", folder / "rest.csv", "--pmax", "1")
    capsys.readouterr()
    assert cli(*args, "--temps", "T1,T2,T3,T4", "--out", folder / "cmp", "--quiet") == 0
    assert "rest continues first (its first time stamp one sampling period after the last)" in capsys.readouterr().out


def test_the_first_rows_date_time_is_kept_with_the_run_and_a_time_of_day_names_no_date(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:50]
    dated(frame, FORMS["day first"]).to_csv(tmp_path / "dated.csv", index=False)
    dated(frame, lambda t: t.strftime("%H:%M:%S")).to_csv(tmp_path / "of_day.csv", index=False)
    run = load_run(tmp_path / "dated.csv", temps=["T1"], time="Timestamp")
    assert run.clock_origin_s == START.tz_localize("UTC").timestamp() and run.time[0] == 0.0
    assert load_run(tmp_path / "of_day.csv", temps=["T1"], time="Timestamp").clock_origin_s is None
    assert load_run(DATASETS / "paper_cycle.csv", temps=["T1"]).clock_origin_s is None


def test_a_model_file_with_a_bad_clock_origin_is_refused(rolled, tmp_path):
    folder, _ = rolled
    model = json.loads((folder / "model.json").read_text())
    model["training"]["recordings"][0]["clock_origin_s"] = "yesterday"
    (tmp_path / "bad.json").write_text(json.dumps(model))
    with pytest.raises(InputError, match=r"training.recordings\[0\].clock_origin_s must be"):
        ModelFile.load(tmp_path / "bad.json")
