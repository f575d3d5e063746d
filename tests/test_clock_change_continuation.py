"""A next file of a log stamped in local time without a UTC offset continues the modelling file across a change
to or from summer time, wherever the change falls: checked against the same files stamped with their offsets."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support.clocks import cli, needs_zones

from groupfit.continuation import clock_continues, restamped
from groupfit.data import load_runs
from groupfit.errors import InputError
from groupfit.model import ModelFile
from groupfit.recordings import overlap_note

DATASETS = Path(__file__).resolve().parents[1] / "groupfit" / "_data" / "datasets"
QUICK = ["--reference", "none", "--quiet", "--p", "0", "--ridge", "0", "--recalibrate", "none"]
ROWS, CHANGE_ROW = 240, 120
CHANGES = {
    "back": ("2026-10-25 01:00:00", "Europe/Berlin"),  # 03:00 CEST back to 02:00 CET
    "ahead": ("2026-03-29 01:00:00", "Europe/Berlin"),  # 02:00 CET ahead to 03:00 CEST
}
CUTS = {"before": (60,), "after": (180,), "at": (CHANGE_ROW,)}
"""Where the modelling file ends: before the change (the next file crosses it), after it (the modelling file
crosses it), and at it (the next file starts with the first row after the change)."""

pytestmark = needs_zones


def split_logs(folder: Path, change: str, cuts: tuple[int, ...]) -> dict[str, list[Path]]:
    """The FE paper cycle's first rows, the clock changing at row ``CHANGE_ROW`` (0-based), cut into files at
    ``cuts``: stamped in wall-clock time (``"wall"``) and with their UTC offsets (``"offset"``)."""
    utc_change, zone = CHANGES[change]
    log = pd.read_csv(DATASETS / "paper_cycle.csv").iloc[:ROWS]
    period = float(log["time_s"].diff().median())
    utc = pd.Timestamp(utc_change, tz="UTC") + pd.to_timedelta(log["time_s"] - CHANGE_ROW * period, unit="s")
    local = utc.dt.tz_convert(zone)
    offsets = local.map(lambda t: t.utcoffset().total_seconds()).to_numpy()
    assert np.flatnonzero(np.diff(offsets)).tolist() == [CHANGE_ROW - 1], "the clock changes before CHANGE_ROW"
    stamps = {"wall": local.dt.strftime("%Y-%m-%d %H:%M:%S"), "offset": local.map(lambda t: t.isoformat())}
    files: dict[str, list[Path]] = {}
    for kind, stamped in stamps.items():
        table = log.assign(time_s=stamped).rename(columns={"time_s": "Timestamp"})
        bounds = [0, *cuts, ROWS]
        files[kind] = []
        for k, (start, end) in enumerate(zip(bounds[:-1], bounds[1:])):
            path = folder / f"{kind}_{'ABC'[k]}.csv"
            table.iloc[start:end].to_csv(path, index=False)
            files[kind].append(path)
    return files


def replayed(tmp_path: Path, capsys, model: Path, data: Path, *more: str) -> tuple[dict, str]:
    """The replay's JSON result and what it printed."""
    report = tmp_path / f"{data.stem}.replay.json"
    assert cli("replay", model, "--data", data, "--time", "Timestamp", "--json", report, *more) == 0
    captured = capsys.readouterr()
    return json.loads(report.read_text()), captured.out + captured.err


def fitted(tmp_path: Path, path: Path) -> Path:
    folder = tmp_path / f"{path.stem}_model"
    assert cli("fit", "--data", path, "--time", "Timestamp", *QUICK, "--out", folder) == 0
    return folder / "model.json"


def residuals(result: dict) -> list:
    return [sample["residual_um"] for sample in result["samples"]]


@pytest.mark.parametrize("cut", sorted(CUTS))
@pytest.mark.parametrize("change", sorted(CHANGES))
def test_the_next_file_continues_the_modelling_file_as_its_twin_stamped_with_offsets_does(
    tmp_path, capsys, change, cut
):
    files = split_logs(tmp_path, change, CUTS[cut])
    results = {}
    for kind, (first, rest) in files.items():
        result, printed = replayed(tmp_path, capsys, fitted(tmp_path, first), rest)
        assert f"{rest.stem}'s clock continues the modelling recording" in printed, printed
        results[kind] = result
    wall, offset = results["wall"], results["offset"]
    assert [Path(p).name for p in wall["continues"]] == ["wall_A.csv"]
    assert [Path(p).name for p in offset["continues"]] == ["offset_A.csv"]
    assert wall["history_samples"] == offset["history_samples"] == CUTS[cut][0]
    assert residuals(wall) == residuals(offset)  # bit for bit: the same rows judged with the same history


@pytest.mark.parametrize("change", sorted(CHANGES))
def test_a_next_file_crossing_the_change_read_with_resample_continues_the_modelling_file(tmp_path, capsys, change):
    files = split_logs(tmp_path, change, CUTS["before"])
    results = {}
    for kind, (first, rest) in files.items():
        result, printed = replayed(tmp_path, capsys, fitted(tmp_path, first), rest, "--resample", "100")
        assert f"{rest.stem}'s clock continues the modelling recording" in printed, printed
        results[kind] = result
    assert results["wall"]["history_samples"] == results["offset"]["history_samples"]
    assert residuals(results["wall"]) == residuals(results["offset"])


@pytest.mark.parametrize("change", sorted(CHANGES))
def test_the_resampled_run_keeps_the_shift_its_clock_change_applied(tmp_path, change):
    files = split_logs(tmp_path, change, CUTS["before"])
    [wall], [offset] = (load_runs(files[kind][1], time="Timestamp", resample=100.0) for kind in ("wall", "offset"))
    stamps = pd.read_csv(files["offset"][1])["Timestamp"]
    first, last = (pd.Timestamp(stamps.iloc[k]).utcoffset().total_seconds() for k in (0, -1))
    assert wall.clock_shift_s == last - first and offset.clock_shift_s is None
    assert wall.first_clock_origin_s - offset.clock_origin_s == first  # the first row's own wall-clock time


def test_a_file_continuing_one_that_crosses_the_change_is_told_so_after_it(tmp_path, capsys):
    """Three files, the middle one crossing the end of summer time: each goes on from the one before by its
    clock, with the wall-clock stamps as with the offsets."""
    files = split_logs(tmp_path, "back", (80, 160))
    results = {}
    for kind, (first, second, third) in files.items():
        model = fitted(tmp_path, first)
        result, printed = replayed(tmp_path, capsys, model, third, "--continues", first, second)
        for earlier, later in ((first, second), (second, third)):
            told = f"{later.stem} continues {earlier.stem} (its first time stamp one sampling period after the last)"
            assert told in printed, printed
        results[kind] = result
    assert results["wall"]["history_samples"] == results["offset"]["history_samples"] == 160
    assert residuals(results["wall"]) == residuals(results["offset"])


@pytest.mark.parametrize("change", sorted(CHANGES))
def test_a_restamped_run_crossing_the_change_keeps_its_date_times_for_the_file_after_it(tmp_path, change):
    """Restamping a run onto the clock of the run it continues leaves its rows at the date-times they had, in the
    clock of its first row and of its last, so the file after it still goes on from it."""
    files = split_logs(tmp_path, change, (80, 160))
    for kind in ("wall", "offset"):
        first, second, third = (load_runs(path, time="Timestamp")[0] for path in files[kind])
        moved = restamped(second, first)
        for times in (lambda r: r.first_clock_origin_s + r.time[0], lambda r: r.clock_origin_s + r.time[-1]):
            assert times(moved) == pytest.approx(times(second), abs=1e-6)
        assert clock_continues(first, second) and clock_continues(moved, third) and clock_continues(second, third)


def test_the_model_file_keeps_the_shift_and_an_older_one_without_it_still_serves(tmp_path, capsys):
    files = split_logs(tmp_path, "back", CUTS["after"])
    model_path = fitted(tmp_path, files["wall"][0])
    data = json.loads(model_path.read_text())
    [entry] = data["training"]["recordings"]
    assert entry["clock_shift_s"] == -3600.0
    assert (
        "clock_shift_s" not in json.loads(fitted(tmp_path, files["offset"][0]).read_text())["training"]["recordings"][0]
    )
    del entry["clock_shift_s"]  # as a model file written before the shift was kept
    model_path.write_text(json.dumps(data))
    _, printed = replayed(tmp_path, capsys, model_path, files["wall"][1])
    assert "wall_B's clock continues the modelling recording" in printed
    entry["clock_shift_s"] = "an hour"
    with pytest.raises(InputError, match=r"training.recordings\[0\].clock_shift_s must be"):
        ModelFile.from_dict(data)


def test_a_file_starting_where_a_modelling_file_crossing_the_change_starts_overlaps_it(tmp_path):
    """The modelling file crosses the end of summer time; a file of its first rows, not crossing it, starts at
    the same wall-clock time: the two overlap, as they do stamped with offsets."""
    files = split_logs(tmp_path, "back", CUTS["after"])
    for kind in ("wall", "offset"):
        first = files[kind][0]
        model = ModelFile.load(fitted(tmp_path, first))
        part = tmp_path / f"{kind}_part.csv"
        pd.read_csv(first).iloc[:60].to_csv(part, index=False)
        [run] = load_runs(part, time="Timestamp")
        assert overlap_note(model.training, run) is not None, kind
