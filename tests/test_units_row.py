"""A row of units under the header read as the units of its columns: the truth is the same run written in µm,
s and °C without a units row."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from test_switching_models import DATASETS, SYNTHETIC

from groupfit.cli import main
from groupfit.data import load_run, load_runs
from groupfit.data_options import split_names
from groupfit.errors import InputError
from groupfit.units_row import unit_of

TEMPS = ["T1", "T2", "T3", "T4"]


def with_units_row(frame: pd.DataFrame, units: dict[str, str]) -> str:
    header, body = frame.to_csv(index=False).split("\n", 1)
    return header + "\n" + ",".join(units.get(c, "") for c in frame.columns) + "\n" + body


@pytest.mark.parametrize(
    "unit, per_um", [("mm", 1e-3), ("[mm]", 1e-3), ("nm", 1e3), ("µm", 1.0), ("um", 1.0), ("(microns)", 1.0)]
)
def test_an_error_in_the_unit_of_its_units_row_is_read_in_micrometres(tmp_path, synthetic, unit, per_um):
    frame, plain = synthetic
    logged = frame.assign(error_um=frame["error_um"] * per_um).rename(columns={"error_um": "Error"})
    path = tmp_path / "log.csv"
    path.write_text(with_units_row(logged, {"time_s": "s", "Error": unit, **dict.fromkeys(TEMPS, "°C")}))
    run = load_run(path, temps=TEMPS, error="Error")
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(run.temps, plain.temps)
    converted = any(f"'Error' from {unit.strip('[]()').lower()}" in note for note in run.notes)
    assert converted == (per_um != 1.0)


@pytest.mark.parametrize("unit, per_second", [("min", 1 / 60), ("h", 1 / 3600), ("[ms]", 1e3), ("s", 1.0)])
def test_a_time_column_in_the_unit_of_its_units_row_is_read_in_seconds(tmp_path, synthetic, unit, per_second):
    frame, plain = synthetic
    logged = frame.assign(time_s=frame["time_s"] * per_second).rename(columns={"time_s": "Time"})
    path = tmp_path / "log.csv"
    path.write_text(with_units_row(logged, {"Time": unit, "error_um": "µm"}))
    run = load_run(path, temps=TEMPS, time="Time")
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)
    assert run.period == pytest.approx(plain.period, rel=1e-9)
    assert not any("the run lasts" in note for note in run.notes)


@pytest.mark.parametrize("unit", ["degF", "°F", "K", "[K]"])
def test_temperatures_in_fahrenheit_or_kelvin_by_the_units_row_are_read_in_celsius(tmp_path, synthetic, unit):
    frame, plain = synthetic
    celsius = frame[TEMPS].to_numpy(dtype=float)
    logged = celsius * 9.0 / 5.0 + 32.0 if "F" in unit else celsius + 273.15
    path = tmp_path / "log.csv"
    path.write_text(with_units_row(frame.assign(**dict(zip(TEMPS, logged.T))), dict.fromkeys(TEMPS, unit)))
    run = load_run(path, temps=TEMPS)
    np.testing.assert_allclose(run.temps, plain.temps, rtol=0, atol=1e-9)
    fitted = tmp_path / "model"
    plain_model = tmp_path / "plain"
    argv = ["--temps", ",".join(TEMPS), "--p", "0", "--ridge", "0", "--seed", "1"]
    assert main(["fit", "--data", str(path), "--out", str(fitted), *argv]) == 0
    assert main(["fit", "--data", str(SYNTHETIC), "--out", str(plain_model), *argv]) == 0
    ours, theirs = (json.loads((out / "model.json").read_text())["coefficients"] for out in (fitted, plain_model))
    np.testing.assert_allclose(ours, theirs, rtol=1e-7, atol=1e-9)


def test_a_logger_table_of_channels_finds_its_error_by_the_units_row_and_names_two_candidates(tmp_path, synthetic):
    frame, plain = synthetic
    channels = {"T1": "CH1", "T2": "CH2", "T3": "CH3", "T4": "CH4", "error_um": "CH5"}
    logged = frame.assign(error_um=frame["error_um"] / 1000.0).rename(columns=channels)
    units = {"time_s": "s", **dict.fromkeys(["CH1", "CH2", "CH3", "CH4"], "degC"), "CH5": "mm"}
    path = tmp_path / "log.csv"
    path.write_text(with_units_row(logged, units))
    run = load_run(path, temps=["CH1", "CH2", "CH3", "CH4"], error_is_default=True)
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)
    assert any("thermal error from column 'CH5'" in note for note in run.notes)
    path.write_text(with_units_row(logged.assign(CH6=logged["CH5"]), {**units, "CH6": "mm"}))
    with pytest.raises(InputError, match=r"2 could be the thermal error \(CH5, CH6\)"):
        load_run(path, temps=["CH1", "CH2", "CH3", "CH4"], error_is_default=True)


def test_a_name_and_a_units_row_that_disagree_are_refused_naming_both(tmp_path, synthetic):
    frame = synthetic[0]
    path = tmp_path / "log.csv"
    path.write_text(with_units_row(frame, {"error_um": "mm"}))
    with pytest.raises(InputError, match=r"column 'error_um' is named in um but the row of units .* gives 'mm'"):
        load_run(path, temps=TEMPS)
    path.write_text(with_units_row(frame.rename(columns={"time_s": "Zeit [min]"}), {"Zeit [min]": "s"}))
    with pytest.raises(InputError, match=r"column 'Zeit \[min\]' is named in min but the row of units"):
        load_run(path, temps=TEMPS, time="Zeit [min]")


def test_a_workbook_units_row_converts_as_a_text_tables_does(tmp_path, synthetic):
    frame, plain = synthetic
    units = {"Time": "min", "Error": "mm"}
    logged = frame.assign(time_s=frame["time_s"] / 60.0, error_um=frame["error_um"] / 1000.0)
    logged = logged.rename(columns={"time_s": "Time", "error_um": "Error"})
    path = tmp_path / "log.xlsx"
    row = pd.DataFrame([{c: units.get(c, "°C") for c in logged.columns}])
    pd.concat([row, logged.astype(object)], ignore_index=True).to_excel(path, index=False)
    run = load_run(path, temps=TEMPS, time="Time", error="Error")
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)


def test_cells_that_are_no_unit_convert_nothing():
    assert [unit_of(cell) for cell in ("rpm", "%", "front bearing", "", "V")] == [None] * 5
    assert unit_of(" [µm] ") == ("length", "µm") and unit_of("Min.") == ("time", "min")


@pytest.mark.parametrize("unit, per_um", [("µm", 1.0), ("mm", 1e-3), (" [nm]", 1e3)])
def test_units_written_in_every_cell_are_read_as_a_row_of_units(tmp_path, synthetic, unit, per_um):
    frame, plain = synthetic
    cells = frame.astype(object).rename(columns={"error_um": "Error"})
    for column in TEMPS:
        cells[column] = [f"{value} °C" for value in frame[column]]
    cells["Error"] = [f"{value * per_um!r}{unit}" for value in frame["error_um"]]
    path = tmp_path / "log.csv"
    cells.to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, error="Error")
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)
    assert any("'Error' from" in note for note in run.notes) == (per_um != 1.0)


@pytest.mark.parametrize(
    "form",
    ["unicode minus", "spaced thousands", "apostrophe thousands", "no-break thousands", "savetxt", "matlab"],
)
def test_numbers_and_headers_as_other_programs_write_them_are_read_as_the_plain_table(tmp_path, synthetic, form):
    frame, plain = synthetic
    speed = frame.assign(speed=np.where(frame["spindle_on"] > 0, -12500.5, 0.0))  # a direction of rotation
    text = speed.to_csv(index=False)
    if form == "unicode minus":
        assert ",-" in text
        text = text.replace(",-", ",\u2212")
    elif form == "spaced thousands":
        text = speed.to_csv(index=False, sep=";", decimal=",").replace("12500,5", "12 500,5")
    elif form == "apostrophe thousands":
        text = text.replace("12500.5", "12'500.5")
    elif form == "no-break thousands":
        text = speed.to_csv(index=False, sep=";", decimal=",").replace("12500,5", "12\u202f500,5")
    elif form == "savetxt":  # NumPy's savetxt(header=...) marks its header as a comment
        text = "# " + text
    else:  # MATLAB's % comment before the names, columns split by spaces
        text = "% " + speed.to_csv(index=False, sep=" ")
    path = tmp_path / "log.csv"
    path.write_text(text, encoding="utf-8")
    run = load_run(path, temps=TEMPS)
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.error, plain.error)
    np.testing.assert_array_equal(run.time, plain.time)
    np.testing.assert_array_equal(run.frame["speed"].to_numpy(dtype=float), speed["speed"].to_numpy())


def test_a_column_named_hash_alone_is_a_name_not_a_comment_mark(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "hobo.csv"
    frame.rename_axis("#").reset_index().assign(**{"#": lambda f: f["#"] + 1}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS)
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.frame["#"].to_numpy(), np.arange(1, len(frame) + 1))


def test_a_hobo_export_is_read_with_its_two_digit_year_and_its_event_columns(tmp_path, synthetic):
    frame, plain = synthetic
    stamps = pd.Timestamp("2026-03-01 08:00:00") + pd.to_timedelta(frame["time_s"] - frame["time_s"].iloc[0], unit="s")
    names = [f"Temp, °C (LGR S/N: 20{k}, SEN S/N: 20{k})" for k in range(1, 5)]
    log = pd.DataFrame(
        {"#": np.arange(1, len(frame) + 1), "Date Time, GMT+01:00": stamps.dt.strftime("%m/%d/%y %I:%M:%S %p")}
    )
    log = log.assign(**dict(zip(names, frame[TEMPS].to_numpy().T)), **{"Z drift, µm": frame["error_um"]})
    log["Coupler Detached (LGR S/N: 201)"] = ["Logged"] + [""] * (len(frame) - 1)
    path = tmp_path / "hobo.csv"
    path.write_text('"Plot Title: spindle"\n' + log.to_csv(index=False, quoting=1))
    run = load_run(path, temps=names, time_is_default=True, error_is_default=True)
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.error, plain.error)
    np.testing.assert_allclose(run.time - run.time[0], plain.time - plain.time[0], rtol=0, atol=1e-9)


def test_names_holding_commas_are_given_in_quotes_and_a_name_cut_at_its_comma_says_so(tmp_path, synthetic):
    frame = synthetic[0]
    names = [f"Temp, °C (S/N {k})" for k in range(1, 5)]
    path = tmp_path / "log.csv"
    frame.rename(columns=dict(zip(TEMPS, names))).to_csv(path, index=False)
    listed = ", ".join(f'"{name}"' for name in names[:2])
    assert split_names(listed) == names[:2]
    assert split_names("T1, T2 ,T3") == ["T1", "T2", "T3"]
    out = tmp_path / "model"
    assert main(["fit", "--data", str(path), "--temps", listed, "--p", "0", "--out", str(out)]) == 0
    assert json.loads((out / "model.json").read_text())["temps"][:2] == names[:2]
    with pytest.raises(InputError, match=r"column 'Temp' not found \(a name with a comma in it is quoted in a list"):
        load_run(path, temps=split_names(names[0]))


@pytest.mark.parametrize("suffix", [".xls", ".xlsx", ".ods"])
def test_a_text_table_saved_under_a_workbooks_name_is_read_as_text(tmp_path, synthetic, suffix):
    frame, plain = synthetic
    path = tmp_path / f"export{suffix}"
    frame.to_csv(path, sep="\t", index=False)  # a web export's "Excel" file: tab-separated text
    same = load_run(path, temps=TEMPS)
    np.testing.assert_array_equal(same.temps, plain.temps)
    np.testing.assert_array_equal(same.error, plain.error)


def test_a_binary_workbook_whose_reader_is_missing_names_the_package_to_install(tmp_path, monkeypatch):
    path = tmp_path / "old.xls"
    path.write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + bytes(600))  # an Excel 97-2003 compound file

    def missing(*args, **kwargs):
        raise ImportError("Missing optional dependency 'xlrd'.  Use pip or conda to install xlrd.")

    monkeypatch.setattr(pd, "read_excel", missing)
    with pytest.raises(InputError, match=r"old.xls: reading Excel files needs the package 'xlrd'; pip install it"):
        load_run(path, temps=TEMPS)


def test_an_opendocument_spreadsheet_is_read_as_a_workbook(tmp_path, synthetic):
    frame, plain = synthetic
    pytest.importorskip("odf")
    path = tmp_path / "log.ods"
    with pd.ExcelWriter(path, engine="odf") as book:
        pd.DataFrame({"Machine": ["lathe 7"]}).to_excel(book, sheet_name="Cover", index=False)
        frame.to_excel(book, sheet_name="Log", index=False)
    run = load_run(path, temps=TEMPS)
    np.testing.assert_allclose(run.temps, plain.temps, rtol=1e-12)
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12)
    assert "sheet 'Log'" in run.source


@pytest.mark.parametrize("suffix", [" [°F]", "_degF", " (K)", ", °F (LGR S/N: 2001)"])
def test_temperatures_named_in_fahrenheit_or_kelvin_are_read_in_celsius(tmp_path, synthetic, suffix):
    frame, plain = synthetic
    celsius = frame[TEMPS].to_numpy(dtype=float)
    logged = celsius + 273.15 if "K" in suffix else celsius * 9.0 / 5.0 + 32.0
    names = [f"{name}{suffix}" for name in TEMPS]
    path = tmp_path / "log.csv"
    frame.drop(columns=TEMPS).assign(**dict(zip(names, logged.T))).to_csv(path, index=False)
    run = load_run(path, temps=split_names(",".join(f'"{name}"' for name in names)))
    np.testing.assert_allclose(run.temps, plain.temps, rtol=0, atol=1e-9)
    assert any(f"'{names[0]}' from" in note for note in run.notes)
    path.write_text(with_units_row(frame.rename(columns={"T1": "T1 [°C]"}), {"T1 [°C]": "degF"}))
    with pytest.raises(InputError, match=r"column 'T1 \[°C\]' is named in °c but its cells or the row of units"):
        load_run(path, temps=["T1 [°C]", "T2"])


def test_differences_in_kelvin_are_read_as_logged(tmp_path, synthetic):
    frame, plain = synthetic
    rise = frame[TEMPS] - frame[TEMPS].iloc[0]  # ΔT [K]: each sensor's rise over its first reading
    path = tmp_path / "log.csv"
    frame.assign(**{f"{name} [K]": rise[name] for name in TEMPS}).drop(columns=TEMPS).to_csv(path, index=False)
    run = load_run(path, temps=[f"{name} [K]" for name in TEMPS])
    np.testing.assert_allclose(run.temps, plain.temps - plain.temps[0], rtol=0, atol=1e-9)
    assert not any("from K" in note for note in run.notes)


def test_units_in_the_cells_of_a_log_with_a_message_line_are_read_once_the_line_is_left_out(tmp_path, synthetic):
    frame, plain = synthetic
    cells = frame.astype(object).rename(columns={"error_um": "Error"})
    cells["Error"] = [f"{value / 1000.0!r} mm" for value in frame["error_um"]]
    lines = cells.to_csv(index=False).splitlines()
    at = list(cells.columns).index("Error")
    lines.insert(120, "," * at + "Logging paused" + "," * (len(cells.columns) - at - 1))  # in the Error column
    path = tmp_path / "log.csv"
    path.write_text("\n".join(lines) + "\n")
    run = load_run(path, temps=TEMPS, error="Error")
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)
    assert any("holding a message alone left out" in note for note in run.notes)
    assert any("'Error' from mm" in note for note in run.notes)


def test_an_air_temperature_named_in_fahrenheit_is_the_reference_as_one_in_celsius(tmp_path):
    frame = pd.read_csv(DATASETS / "paper_cycle.csv")  # the FE run, its inputs taken over T_amb
    sensors = [name for name in frame.columns if name.startswith("T")]
    fahrenheit = tmp_path / "f.csv"
    in_f = {f"{name} [°F]": frame[name] * 1.8 + 32.0 for name in sensors}
    frame.drop(columns=sensors).assign(**in_f).to_csv(fahrenheit, index=False)
    models = []
    for path, folder in ((DATASETS / "paper_cycle.csv", tmp_path / "c"), (fahrenheit, tmp_path / "f")):
        assert main(["fit", "--data", str(path), "--p", "0", "--ridge", "0", "--out", str(folder)]) == 0
        models.append(json.loads((folder / "model.json").read_text()))
    assert models[0]["reference"] == "T_amb" and models[1]["reference"] == "T_amb [°F]"
    np.testing.assert_allclose(models[1]["coefficients"], models[0]["coefficients"], rtol=1e-6, atol=1e-8)


def test_units_written_in_the_cells_of_a_workbook_are_read_as_in_a_text_table(tmp_path, synthetic):
    frame, plain = synthetic
    cells = frame.astype(object).rename(columns={"error_um": "Error"})
    cells["Error"] = [f"{value / 1000.0!r} mm" for value in frame["error_um"]]
    path = tmp_path / "log.xlsx"
    cells.to_excel(path, index=False)
    run = load_run(path, temps=TEMPS, error="Error")
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize(
    "name, flagged",
    [("105 (VDC)", True), ("probe [mV]", True), ("Z [counts]", True), ("drift A", False), ("dZ [µm]", False)],
)
def test_an_error_named_in_a_transducers_signal_unit_gets_a_note_to_scale_it(tmp_path, synthetic, name, flagged):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.rename(columns={"error_um": name}).to_csv(path, index=False)
    run = load_run(path, temps=TEMPS, error=name)
    np.testing.assert_array_equal(run.error, plain.error)  # read as logged, in µm
    assert any("a transducer's signal, not a length" in note for note in run.notes) == flagged


@pytest.mark.parametrize("message", [False, True])
def test_units_after_dotted_numbers_in_a_table_of_decimal_commas_are_refused_with_or_without_a_message_line(
    tmp_path, synthetic, message
):
    frame, _ = synthetic
    lines = frame.to_csv(index=False, sep=";", decimal=",").splitlines()
    at = list(frame.columns).index("T1")
    for k in range(1, len(lines)):
        cells = lines[k].split(";")
        cells[at] = f"{frame['T1'].iloc[k - 1]:.2f} °C"  # a decimal point, where the table writes commas
        lines[k] = ";".join(cells)
    if message:
        lines.insert(50, ";" * at + "Logging paused" + ";" * (len(frame.columns) - at - 1))
    path = tmp_path / "log.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        InputError, match=r"log.csv: not a readable CSV table \(column 'T1' holds '\d+\.\d+', a decimal"
    ):
        load_runs(path, temps=TEMPS)


@pytest.mark.parametrize("sep", [",", ";", "\t"])
def test_a_column_empty_under_its_unit_is_read_as_missing(tmp_path, synthetic, sep):
    frame, plain = synthetic
    units = {"time_s": "s", "error_um": "µm", "spare": "-", **dict.fromkeys(TEMPS, "°C")}
    header, body = frame.assign(spare=np.nan).to_csv(index=False, sep=sep).split("\n", 1)
    path = tmp_path / "log.csv"
    path.write_text(header + "\n" + sep.join(units.get(c, "") for c in [*frame.columns, "spare"]) + "\n" + body)
    run = load_run(path, temps=TEMPS)
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.error, plain.error)


def spaced_with_units(frame: pd.DataFrame, units: list[str]) -> str:
    """The table split at single spaces, a units row of ``units`` under its names (as many as given)."""
    lines = [" ".join(frame.columns), " ".join(units)]
    lines += [" ".join(f"{v:.10g}" for v in row) for row in frame.to_numpy(dtype=float)]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("temperature, error", [("°F", "mm"), ("degF", "µm"), ("°C", "mm"), ("K", "nm")])
def test_a_units_row_without_the_times_unit_is_read_as_the_units_of_the_last_columns(
    tmp_path, synthetic, temperature, error
):
    """``°F °F °F °F mm`` under ``time_s T1 T2 T3 T4 error_um spindle_on`` minus the switch column: placed from
    the first column, °F stood over the time (the times converted as temperatures), every unit one column
    off and the error left in mm."""
    frame, plain = synthetic
    celsius = frame[TEMPS].to_numpy(dtype=float)
    logged = {"F": celsius * 9.0 / 5.0 + 32.0, "C": celsius, "K": celsius + 273.15}[temperature[-1]]
    per_um = {"mm": 1e-3, "µm": 1.0, "nm": 1e3}[error]
    table = frame.assign(**dict(zip(TEMPS, logged.T)), error_um=frame["error_um"] * per_um)
    table = table[["time_s", *TEMPS, "error_um"]].rename(columns={"error_um": "error"})
    path = tmp_path / "log.txt"
    path.write_text(spaced_with_units(table, [temperature] * 4 + [error]))
    run = load_run(path, temps=TEMPS, error="error")
    np.testing.assert_allclose(run.time, plain.time, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.temps, plain.temps, rtol=0, atol=1e-6)
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-9, atol=1e-9)
    assert any("5 units for 6 columns" in note and "from 'T1' on" in note for note in run.notes)


def test_a_units_row_that_puts_a_temperature_over_the_time_either_way_is_refused(tmp_path, synthetic):
    frame, _ = synthetic
    table = frame[["time_s", *TEMPS, "error_um"]]
    path = tmp_path / "log.txt"
    path.write_text(spaced_with_units(table, ["°F"] * 6))  # as many units as columns, one over the time
    with pytest.raises(InputError, match=r"puts '°F', a unit of temperature, over the time column 'time_s'"):
        load_run(path, temps=TEMPS)
