import json

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.errors import InputError


def write_run(tmp_path, frame, name="run.csv"):
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path


def good_frame(N=80):
    t = np.arange(1, N + 1) * 100.0
    rng = np.random.default_rng(0)
    return pd.DataFrame(
        {
            "time_s": t,
            "T1": 20 + np.log1p(t / 500.0),
            "T2": 20 + np.sqrt(t / 1000.0),
            "T3": 20 + 0.3 * np.sin(t / 2000.0) + 0.01 * rng.normal(size=N),
            "error_um": 2.0 * np.log1p(t / 700.0),
            "speed_rpm": 2000,
        }
    )


def test_good_run_loads_into_arrays(tmp_path):
    path = write_run(tmp_path, good_frame())
    run = load_run(path, temps=["T1", "T3"])
    assert run.temps.shape == (80, 2) and run.temp_names == ("T1", "T3")
    assert run.period == pytest.approx(100.0) and run.name == "run"
    np.testing.assert_allclose(run.error, good_frame()["error_um"])
    assert load_run(path).temp_names == ("T1", "T2", "T3")  # default: sensor-named columns


def test_dataframe_input_is_accepted():
    run = load_run(good_frame(), temps=["T2"], name="frame")
    assert run.name == "frame" and run.temps.shape == (80, 1)


def mutate(frame, column, row, value):
    frame = frame.astype({column: object})
    frame.loc[row, column] = value
    return frame


CASES = [
    ("missing file", None, "data file not found"),
    ("missing column", lambda f: f.drop(columns="T2"), r"column 'T2' not found"),
    ("non-numeric cell", lambda f: mutate(f, "T2", 11, "abc"), r"row 12, column 'T2': 'abc' is not a number"),
    ("empty cell", lambda f: mutate(f, "T1", 4, ""), r"row 5, column 'T1' is empty"),
    ("infinite value", lambda f: mutate(f, "error_um", 7, np.inf), r"row 8, column 'error_um' is inf"),
    ("time not increasing", lambda f: mutate(f, "time_s", 20, 1900.0), r"not strictly increasing at row 21"),
    ("irregular sampling", lambda f: mutate(f, "time_s", 30, 3050.0), r"sampling is not uniform: rows 30 to 31"),
    ("constant temperature", lambda f: f.assign(T2=21.5), r"column 'T2' is constant \(21.5 °C\)"),
    ("constant error", lambda f: f.assign(error_um=0.0), r"error column 'error_um' is constant \(0 µm\)"),
]


@pytest.mark.parametrize("label, change, message", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_one_clear_line_and_exit_2(tmp_path, capsys, label, change, message):
    path = tmp_path / "missing.csv" if change is None else write_run(tmp_path, change(good_frame()))
    with pytest.raises(InputError, match=message):
        load_run(path, temps=["T1", "T2", "T3"])
    out = tmp_path / "out"
    status = main(["fit", "--data", str(path), "--temps", "T1,T2,T3", "--p", "1", "--out", str(out), "--quiet"])
    captured = capsys.readouterr()
    assert status == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and str(path.name) in lines[0]
    assert "Traceback" not in captured.err
    assert not out.exists() or not any(out.iterdir())


def test_too_few_samples_names_the_largest_feasible_p(tmp_path, capsys):
    path = write_run(tmp_path, good_frame(N=50))
    out = tmp_path / "out"
    status = main(["fit", "--data", str(path), "--temps", "T1,T2,T3", "--p", "3", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2
    assert "p = 3 breaks do not fit N = 50" in err and "the largest feasible p is 2" in err  # 4 groups of 13 need 52
    assert not (out / "model.json").exists()


def test_nonfinite_values_kept_when_allowed(tmp_path):
    path = write_run(tmp_path, mutate(good_frame(), "T1", 3, np.nan))
    run = load_run(path, temps=["T1"], allow_nonfinite=True)
    assert np.isnan(run.temps[3, 0])


def test_error_column_optional_when_not_required(tmp_path):
    path = write_run(tmp_path, good_frame().drop(columns="error_um"))
    assert load_run(path, temps=["T1"], require_error=False).error is None
    with pytest.raises(InputError, match="column 'error_um' not found"):
        load_run(path, temps=["T1"])


def test_unreadable_or_empty_files(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(InputError, match="empty"):
        load_run(empty)
    header_only = tmp_path / "header.csv"
    header_only.write_text("time_s,T1,error_um\n")
    with pytest.raises(InputError, match="no rows"):
        load_run(header_only)


def test_a_printer_hot_end_is_a_reading_and_logger_overflows_are_not(tmp_path):
    """A 3-D printer's hot end (``T0`` at 215 °C) loads; the values broken loggers write are refused."""
    frame = good_frame()
    frame.insert(1, "T0", 215.0 + 0.3 * np.sin(frame["time_s"] / 900.0))
    run = load_run(write_run(tmp_path, frame))
    assert run.temp_names[0] == "T0" and run.temps[:, 0].min() > 200.0
    for fault in (850.0, 9999.0, 3276.7, -273.15):
        path = write_run(tmp_path, mutate(frame, "T0", 7, fault))
        with pytest.raises(InputError, match=r"row 8, column 'T0'.*outside the plausible range"):
            load_run(path)


@pytest.mark.parametrize(
    "column, value, note, refusal",
    [
        ("T0_target", 215.0, "constant over the whole run, left out of the inputs: 'T0_target' (215 °C)", "constant"),
        ("T9", np.nan, "no reading in the whole run, left out of the inputs: 'T9'", "holds no reading in the whole"),
    ],
)
@pytest.mark.parametrize("resample", [None, "period"])
def test_a_constant_or_empty_column_among_the_default_inputs_is_left_out_with_a_note(
    tmp_path, column, value, note, refusal, resample
):
    frame = good_frame().assign(**{column: value})
    period = None if resample is None else float(np.diff(frame["time_s"]).mean())
    run = load_run(write_run(tmp_path, frame), resample=period)  # averaging readings does not drop the column
    assert run.temp_names == ("T1", "T2", "T3")
    np.testing.assert_allclose(run.temps, frame[["T1", "T2", "T3"]].to_numpy())
    assert any(note in line for line in run.notes)
    with pytest.raises(InputError, match=rf"column '{column}' (is )?{refusal}"):  # named: refused
        load_run(write_run(tmp_path, frame), temps=["T1", column], resample=period)


@pytest.mark.parametrize("cells", [["---"], ["OVL", "", "n.a."]])
def test_a_default_input_marked_as_not_read_in_every_row_is_left_out_and_one_of_words_refused(tmp_path, cells):
    frame = good_frame()
    marked = frame.astype({"T3": object}).assign(T3=[cells[k % len(cells)] for k in range(len(frame))])
    run = load_run(write_run(tmp_path, marked))
    assert run.temp_names == ("T1", "T2") and any("no reading in the whole run" in n for n in run.notes)
    units = ("deg", "Grad")  # numbers with words, no one unit: not a channel without readings
    worded = frame.astype({"T3": object}).assign(T3=[f"{v:.2f} {units[k % 2]}" for k, v in enumerate(frame["T3"])])
    with pytest.raises(InputError, match=r"row 1, column 'T3': '[\d.]+ deg' is not a number"):
        load_run(write_run(tmp_path, worded))


def test_a_run_with_no_input_left_or_an_input_with_readings_missed_is_refused(tmp_path):
    dead = good_frame().assign(T1=20.0, T2=20.0, T3=20.0)
    with pytest.raises(InputError, match=r"column 'T1' is constant"):  # nothing left to model with
        load_run(write_run(tmp_path, dead))
    frame = good_frame()
    half = frame.assign(T9=np.where(np.arange(len(frame)) < 5, np.nan, 21.0))
    with pytest.raises(InputError, match=r"row 1, column 'T9' is empty \(5 non-finite"):
        load_run(write_run(tmp_path, half))
    replayed = load_run(write_run(tmp_path, frame.assign(T9=np.nan)), require_error=False, allow_nonfinite=True)
    assert replayed.temp_names == ("T1", "T2", "T3", "T9")  # a replay keeps what it reads


def test_runs_with_other_default_inputs_share_the_inputs_every_run_kept(tmp_path, capsys):
    frame = good_frame()
    first = write_run(tmp_path, frame, "a.csv")
    second = write_run(tmp_path, frame.assign(T3=20.0), "b.csv")  # T3 never moved that day: left out there
    out = tmp_path / "out"
    assert main(["fit", "--data", str(first), str(second), "--p", "0", "--out", str(out), "--quiet"]) == 0
    report = capsys.readouterr().out
    assert "T3 left out of the inputs of every run: loading left it out of " in report and "--temps" in report
    shared = json.loads((out / "model.json").read_text())
    named = tmp_path / "named"
    assert main(["fit", "--data", str(first), str(second), "--temps", "T1,T2", "--p", "0", "--out", str(named)]) == 0
    named_model = json.loads((named / "model.json").read_text())
    assert shared["temps"] == named_model["temps"]
    np.testing.assert_allclose(shared["coefficients"], named_model["coefficients"], rtol=1e-9)
    other = write_run(tmp_path, frame.drop(columns=["T3"]).assign(T4=frame.T3), "c.csv")  # another sensor
    assert main(["fit", "--data", str(first), str(other), "--p", "0", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "c.csv: temperature columns differ from the modelling run's" in err[0]


def test_runs_whose_inputs_come_in_another_column_order_are_joined_by_name(tmp_path, capsys):
    """The same sensors logged in another column order are the same inputs: the global model fitted on both is
    the one fitted with the columns in the first run's order."""
    frame = good_frame()
    first = write_run(tmp_path, frame, "a.csv")
    second = write_run(tmp_path, frame.assign(T1=frame.T1 + 0.3 * np.sin(np.arange(len(frame)))), "b.csv")
    swapped = pd.read_csv(second)
    write_run(tmp_path, swapped[list(swapped.columns[::-1])], "reversed.csv")
    models = []
    for name in ("b.csv", "reversed.csv"):
        out = tmp_path / name.replace(".csv", "")
        assert main(["fit", "--data", str(first), str(tmp_path / name), "--p", "0", "--out", str(out), "--quiet"]) == 0
        models.append(json.loads((out / "model.json").read_text()))
    assert models[0]["temps"] == models[1]["temps"]
    np.testing.assert_allclose(models[0]["coefficients"], models[1]["coefficients"], rtol=1e-12)


@pytest.mark.parametrize("option", ["--reference", "--ambient"])
def test_a_column_named_as_a_speed_is_refused_as_the_reference(tmp_path, capsys, option):
    """Temperatures less r/min fitted without a word (a group constant of 5709); a speed is no temperature."""
    frame = good_frame().assign(spindle_rpm=np.repeat([0.0, 3000.0], 40))
    run = write_run(tmp_path, frame)
    args = ["fit", "--data", str(run), "--temps", "T1,T2", "--p", "0", option, "spindle_rpm"]
    assert main([*args, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'spindle_rpm' is named as a speed, not a temperature" in err[0]
    assert not (tmp_path / "o").exists()
