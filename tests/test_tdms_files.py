"""A run logged as TDMS (LabVIEW, DIAdem, NI loggers) reads as the same run saved as CSV."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

nptdms = pytest.importorskip("nptdms")

from groupfit.cli import main  # noqa: E402
from groupfit.data import load_run  # noqa: E402
from groupfit.errors import InputError  # noqa: E402

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
TEMPS = ["T1", "T2", "T3", "T4"]


def write_tdms(path: Path, groups: dict, *, timing: dict | None = None) -> None:
    """``groups``: group name → {channel name: (values, unit or None)}; ``timing``: waveform properties."""
    objects = [nptdms.RootObject(properties={"name": path.stem})]
    for group, channels in groups.items():
        objects.append(nptdms.GroupObject(group))
        for name, (values, unit) in channels.items():
            properties = dict(timing or {})
            if unit:
                properties["unit_string"] = unit
            objects.append(nptdms.ChannelObject(group, name, np.asarray(values), properties=properties))
    with nptdms.TdmsWriter(path) as writer:
        writer.write_segment(objects)


def paper_cycle_as_tdms(path: Path, *, error=("error_um", 1.0, "um"), temp_unit="°C", to_unit=lambda t: t):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    period = float(np.diff(frame["time_s"])[0])
    name, per_um, unit = error
    others = [c for c in frame.columns if c not in ("time_s", "error_um", *TEMPS)]
    groups = {
        "Temperatures": {t: (to_unit(frame[t].to_numpy()), temp_unit) for t in TEMPS},
        "Displacement": {name: (frame["error_um"].to_numpy() / per_um, unit)},
        "Machine": {c: (frame[c].to_numpy(), None) for c in others},  # T5, T6, T_amb, speed_rpm, spindle_on
    }
    write_tdms(path, groups, timing={"wf_start_offset": 0.0, "wf_increment": period})
    return frame


def test_a_tdms_log_reads_as_the_same_run_saved_as_csv(tmp_path):
    paper_cycle_as_tdms(tmp_path / "run.tdms")
    plain = load_run(DATASETS / "paper_cycle.csv", temps=TEMPS)
    logged = load_run(tmp_path / "run.tdms", temps=TEMPS)
    np.testing.assert_array_equal(logged.time, plain.time)  # from the waveform timing: no time channel
    np.testing.assert_array_equal(logged.temps, plain.temps)
    np.testing.assert_array_equal(logged.error, plain.error)
    assert logged.period == plain.period


def test_units_of_the_channels_are_read_as_a_row_of_units(tmp_path):
    paper_cycle_as_tdms(
        tmp_path / "units.tdms", error=("dZ", 1000.0, "mm"), temp_unit="°F", to_unit=lambda t: t * 1.8 + 32
    )
    plain = load_run(DATASETS / "paper_cycle.csv", temps=TEMPS)
    logged = load_run(tmp_path / "units.tdms", temps=TEMPS, error="dZ")
    np.testing.assert_allclose(logged.error, plain.error, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(logged.temps, plain.temps, rtol=1e-12, atol=1e-12)
    assert any("converted to µm, s and °C" in note and "'dZ' from mm" in note for note in logged.notes)


def test_a_time_channel_is_read_as_logged_and_a_name_shared_by_two_groups_takes_its_group(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    groups = {
        "Log": {"Time": (frame["time_s"].to_numpy() + 3600.0, "s"), **{t: (frame[t].to_numpy(), None) for t in TEMPS}},
        "Probe A": {"dZ": (frame["error_um"].to_numpy(), "um")},
        "Probe B": {"dZ": (-frame["error_um"].to_numpy(), "um")},
    }
    write_tdms(tmp_path / "run.tdms", groups)
    logged = load_run(tmp_path / "run.tdms", temps=TEMPS, time="Time", error="Probe B/dZ")
    np.testing.assert_array_equal(logged.error, -frame["error_um"].to_numpy())
    np.testing.assert_array_equal(logged.time, frame["time_s"].to_numpy() + 3600.0)
    assert "time_s" not in logged.frame.columns


def test_a_channel_of_another_length_is_left_out_and_named_when_asked_for(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")
    groups = {
        "Temperatures": {t: (frame[t].to_numpy(), "°C") for t in TEMPS},
        "Fast": {"dZ": (np.repeat(frame["error_um"].to_numpy(), 10), "um")},  # ten times the rate
    }
    write_tdms(tmp_path / "rates.tdms", groups, timing={"wf_increment": 100.0})
    with pytest.raises(InputError, match=r"column 'dZ' not found.*the columns are: time_s, T1, T2, T3, T4$"):
        load_run(tmp_path / "rates.tdms", temps=TEMPS, error="dZ")


def test_fit_reads_a_tdms_log_as_its_csv_and_a_broken_one_is_refused_in_one_line(tmp_path, capsys):
    paper_cycle_as_tdms(tmp_path / "run.tdms")
    figures = []
    for data in (DATASETS / "paper_cycle.csv", tmp_path / "run.tdms"):
        out = tmp_path / data.suffix.lstrip(".")
        fit = ["fit", "--data", str(data), "--temps", ",".join(TEMPS), "--p", "1", "--search", "exact"]
        assert main([*fit, "--out", str(out), "--json", str(out.with_suffix(".json")), "--quiet"]) == 0
        figures.append(json.loads(out.with_suffix(".json").read_text()))
    assert figures[1]["expected_next_run_rms_um"] == figures[0]["expected_next_run_rms_um"]
    assert figures[1]["breaks"] == figures[0]["breaks"]
    broken = {
        "other.tdms": (
            b"this is a text file, not a TDMS file at all\n",
            "not a readable TDMS file (Segment does not start with b'TDSm'",
        ),
        "cut.tdms": ((tmp_path / "run.tdms").read_bytes()[:30], "holds no channel of numbers or time stamps"),
        "noise.tdms": (b"TDSm\x04\x00\x00\x00" + bytes(range(256)) * 16, "holds no channel of numbers or time stamps"),
    }
    for name, (content, says) in broken.items():
        (tmp_path / name).write_bytes(content)
        capsys.readouterr()
        assert main(["fit", "--data", str(tmp_path / name), "--out", str(tmp_path / "b")]) == 2
        err = capsys.readouterr().err.strip()
        assert f"{name}: {says}" in err and len(err.splitlines()) == 1
        assert not (tmp_path / "b").exists()
