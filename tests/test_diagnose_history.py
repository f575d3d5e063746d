"""A validation file that continues the modelling file is judged with the controller's history carried over."""

import json

import numpy as np
import pytest
from support.diagnose_scenarios import SPINDLE_SENSORS as SENSORS
from support.diagnose_scenarios import global_model, spindle_run

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.history import COLD_START_NOTE, continues
from groupfit.diagnose.notes import COLD_START, HISTORY
from groupfit.diagnose.problem import stacked_residual
from groupfit.models.grouped import GroupedRegressor
from groupfit.runtime import replay_groups

TEMPS = SENSORS[:2]


def split(frame, at):
    """The log cut in two files at row ``at``: the second's time stamps go on from the first's."""
    first = load_run(frame.iloc[:at].reset_index(drop=True), temps=TEMPS, name="monday")
    second = load_run(frame.iloc[at:].reset_index(drop=True), temps=TEMPS, name="monday_evening")
    return first, second


def test_only_a_run_that_starts_one_period_after_another_continues_it():
    frame = spindle_run(7, hours=6.0)
    first, second = split(frame, 400)
    assert continues(first, second) and not continues(second, first)
    later = frame.iloc[400:].copy()
    later["time_s"] += 3600.0  # an hour's gap: the machine may have stood
    assert not continues(first, load_run(later.reset_index(drop=True), temps=TEMPS))
    other_sensors = load_run(frame.iloc[400:].reset_index(drop=True), temps=["T1", "T3"])
    assert not continues(first, other_sensors)
    resampled = frame.iloc[400::2].reset_index(drop=True)  # every 60 s instead of 30 s
    assert not continues(first, load_run(resampled, temps=TEMPS))
    fewer_columns = frame.iloc[400:].drop(columns="T8").reset_index(drop=True)  # another logger set-up
    assert not continues(first, load_run(fewer_columns, temps=TEMPS))


@pytest.mark.parametrize("p", [0, 1], ids=["global", "grouped"])
def test_the_validation_part_of_a_split_log_is_judged_as_if_the_log_were_whole(p):
    frame = spindle_run(8, hours=16.0)
    at = int(np.flatnonzero(frame["speed_rpm"].to_numpy() >= 4000.0)[-1]) - 60  # cut while the spindle runs fast
    modelling, validation = split(frame, at)
    model = GroupedRegressor(p=p).fit(modelling.temps, modelling.error).to_model_file(modelling).to_dict()
    result = diagnose(model, modelling, validation, live_rule=replay_groups)
    assert result.added and result.added[0].feature.column == "speed_rpm"
    assert any(note.startswith("monday_evening continues monday") for note in result.notes_of(HISTORY))

    # the independent path: the whole log, the error of the modelling rows left empty, the first rows dropped
    whole = frame.copy()
    whole.loc[: at - 1, "error_um"] = np.nan
    whole_run = load_run(whole, temps=TEMPS, name="whole", allow_nonfinite=True)
    expected = stacked_residual(result.model, [whole_run], replay_groups)[at:]
    np.testing.assert_allclose(result.residuals_after["validate"], expected, rtol=0, atol=1e-12)
    assert len(result.residuals_after["validate"]) == len(validation.time)
    # judged from rest instead, the speed's low-pass starts cold on a hot machine
    from_rest = stacked_residual(result.model, [validation], replay_groups)
    assert np.sqrt(np.mean(from_rest**2)) > 1.5 * np.sqrt(np.mean(expected**2))


def test_diagnose_on_files_says_the_validation_run_continues_the_modelling_run(tmp_path, capsys):
    frame = spindle_run(9, hours=12.0)
    paths = [tmp_path / "part1.csv", tmp_path / "part2.csv"]
    frame.iloc[:900].to_csv(paths[0], index=False)
    frame.iloc[900:].to_csv(paths[1], index=False)
    fit = ["fit", "--data", str(paths[0]), "--temps", ",".join(TEMPS), "--p", "0", "--reference", "none"]
    assert main([*fit, "--quiet", "--out", str(tmp_path / "m")]) == 0
    capsys.readouterr()
    args = ["diagnose", str(tmp_path / "m" / "model.json"), "--data", str(paths[0]), "--validate", str(paths[1])]
    assert main([*args, "--out", str(tmp_path / "d"), "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert any(note.startswith("part2 continues part1") for note in result["notes"])
    assert result["after"]["validate"]["rms_um"] < result["before"]["validate"]["rms_um"]


def test_a_validation_run_after_a_gap_starts_from_rest():
    frame = spindle_run(10, hours=10.0)
    modelling, _ = split(frame, 600)
    later = frame.iloc[600:].copy()
    later["time_s"] += 3600.0  # the machine stood for an hour: the controller started again
    validation = load_run(later.reset_index(drop=True), temps=TEMPS, name="later")
    model = global_model(modelling)
    result = diagnose(model, modelling, validation, live_rule=replay_groups)
    assert not any(note.startswith("later continues") for note in result.notes_of(HISTORY))
    np.testing.assert_allclose(
        result.residuals_after["validate"], stacked_residual(result.model, [validation], replay_groups), atol=1e-12
    )


def test_a_chain_of_files_carries_the_history_through_every_one():
    frame = spindle_run(11, hours=12.0)
    parts = [frame.iloc[a:b].reset_index(drop=True) for a, b in ((0, 700), (700, 1000), (1000, None))]
    modelling, *validation = [load_run(p, temps=TEMPS, name=f"part{k}") for k, p in enumerate(parts)]
    model = global_model(modelling)
    result = diagnose(model, modelling, validation, live_rule=replay_groups)
    assert [n.split(" (")[0] for n in result.notes_of(HISTORY) if "continues" in n] == [
        "part1 continues part0",
        "part2 continues part1",
    ]
    whole = frame.copy()
    whole.loc[:699, "error_um"] = np.nan
    whole_run = load_run(whole, temps=TEMPS, name="whole", allow_nonfinite=True)
    expected = stacked_residual(result.model, [whole_run], replay_groups)[700:]
    np.testing.assert_allclose(result.residuals_after["validate"], expected, rtol=0, atol=1e-12)


def test_a_validation_file_that_starts_hot_without_its_history_is_said_to():
    # the log cut while the spindle runs fast, the second file's clock started again 20 min later: its lag of
    # the speed starts from rest on a hot machine, and the report says why the validation may look worse
    frame = spindle_run(8, hours=16.0)
    speed = frame["speed_rpm"].to_numpy()
    at = int(np.flatnonzero(speed >= 4000.0)[-1]) - 60
    modelling, _ = split(frame, at)
    model = global_model(modelling)

    def diagnosed_from(row):
        later = frame.iloc[row:].reset_index(drop=True)
        later["time_s"] -= later["time_s"].iloc[0]  # the logger's clock started again
        return diagnose(model, modelling, load_run(later, temps=TEMPS, name="evening"), live_rule=replay_groups)

    paused = at + 40
    hot = diagnosed_from(paused)
    assert not [n for n in hot.notes_of(HISTORY) if "continues" in n]  # not where the modelling file left off
    assert hot.added[0].feature.column == "speed_rpm" and hot.added[0].feature.start == "rest"
    said = hot.notes_of(COLD_START)
    assert len(said) == 1 and said[0].startswith(f"evening {COLD_START_NOTE} speed_rpm = {speed[paused]:g}")
    lines = hot.summary().splitlines()
    if lines[0].startswith("the augmented model is worse"):
        assert lines[1] == f"  ({said[0]})" and not any(line == f"note: {said[0]}" for line in lines)
    else:
        assert f"note: {said[0]}" in lines

    cold_row = int(np.flatnonzero(speed[:at] == 0.0)[-1])  # a file that starts with the spindle stopped
    assert not diagnosed_from(cold_row).notes_of(COLD_START)


def test_a_restarted_clock_is_the_rest_of_the_recording_by_its_first_row_or_by_continues(tmp_path, capsys):
    """The second file's clock starts again at 0: where its first row picks up the modelling file's last, it
    continues it unasked; after a pause, from rest without the flag and as the continuing log with it."""
    frame = spindle_run(8, hours=16.0)
    at = int(np.flatnonzero(frame["speed_rpm"].to_numpy() >= 4000.0)[-1]) - 60  # cut while the spindle runs fast
    paths = {name: tmp_path / f"{name[0]}.csv" for name in ("modelling", "continuing", "restarted", "paused")}
    frame.iloc[:at].to_csv(paths["modelling"], index=False)
    frame.iloc[at:].to_csv(paths["continuing"], index=False)
    for name, row in (("restarted", at), ("paused", at + 40)):
        later = frame.iloc[row:].reset_index(drop=True)
        later["time_s"] -= later["time_s"].iloc[0]
        later.to_csv(paths[name], index=False)
    fit = ["fit", "--data", str(paths["modelling"]), "--temps", ",".join(TEMPS), "--p", "0", "--reference", "none"]
    assert main([*fit, "--quiet", "--out", str(tmp_path / "m")]) == 0
    capsys.readouterr()

    def diagnosed(validation, *flags):
        args = ["diagnose", str(tmp_path / "m" / "model.json"), "--data", str(paths["modelling"])]
        assert (
            main([*args, "--validate", str(paths[validation]), *flags, "--json", "-", "--out", str(tmp_path / "d")])
            == 0
        )
        return json.loads(capsys.readouterr().out)

    as_logged = diagnosed("continuing")
    picked_up = diagnosed("restarted")
    declared = diagnosed("restarted", "--continues")
    for other in (picked_up, declared):
        assert other["validation_runs"] == [{**as_logged["validation_runs"][0], "name": "r"}]
    assert declared["added"] == as_logged["added"] == picked_up["added"]
    for other in (picked_up, declared):  # told by the first row, --continues or not
        assert any(n.startswith("r continues m (its clock starts again, but its first row") for n in other["notes"])
    from_rest, paused_declared = diagnosed("paused"), diagnosed("paused", "--continues")
    assert from_rest["added"] == as_logged["added"]
    assert any(COLD_START_NOTE in n and "--continues" in n for n in from_rest["notes"])
    assert any(n.startswith("p is taken to continue m (--continues)") for n in paused_declared["notes"])
    assert from_rest["after"]["validate"]["rms_um"] > paused_declared["after"]["validate"]["rms_um"]
    # replay says the same of the augmented model's lag of the speed: started from rest on the paused file alone
    augmented = tmp_path / "d" / "model_augmented.json"
    for name, said in (("paused", True), ("restarted", False)):
        assert main(["replay", str(augmented), "--data", str(paths[name]), "--json", str(tmp_path / "r.json")]) == 0
        notes = [line for line in capsys.readouterr().out.splitlines() if COLD_START_NOTE in line]
        assert len(notes) == int(said) and all("the derived input's heat law" in line for line in notes)
    # another recording cannot be declared the rest of this one: one line, exit 2
    other = frame.iloc[at:].drop(columns="T8")
    other.to_csv(tmp_path / "d.csv", index=False)
    args = ["diagnose", str(tmp_path / "m" / "model.json"), "--data", str(paths["modelling"]), "--continues"]
    assert main([*args, "--validate", str(tmp_path / "d.csv"), "--out", str(tmp_path / "x")]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "--continues, but it cannot be the rest of m" in error[0]
    assert not (tmp_path / "x").exists()
