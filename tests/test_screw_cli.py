"""``groupfit screw identify | predict | compare`` and their bad-input messages."""

import json
from pathlib import Path

import pandas as pd
import pytest

from groupfit.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets"


def run_cli(args, capsys):
    status = main(args)
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("screw")
    assert main(["screw", "identify", str(DATA / "screw_H.csv"), str(DATA / "screw_A.csv"), "--out", str(out)]) == 0
    return out / "screw_model.json"


def test_identify_writes_the_ballscrew_model_file(model_file):
    data = json.loads(model_file.read_text())
    assert data["kind"] == "ballscrew"
    assert data["h_W_m2K"] == pytest.approx(17.2, rel=0.1)
    assert set(data["alpha_prime"]) >= {"a0_m2_s", "a1_m2_sK", "table", "curve", "used"}
    assert data["alpha_prime"]["used"] == data["settings"]["alpha_law"] == "table"
    curve = data["alpha_prime"]["curve"]
    assert curve["t_s"][0] == 5.0 and len(curve["t_s"]) == len(curve["alpha_prime_m2_s"])
    names = [s["name"] for s in data["sources"]]
    assert names == ["screw_H", "screw_A"]
    assert all(isinstance(s["C1"], float) and isinstance(s["C2"], float) for s in data["sources"])
    assert data["sources"][1]["method"] == "first 400 s"


def test_predict_reidentifies_a_new_source_and_reports_the_papers_metrics(model_file, tmp_path, capsys):
    status, out, err = run_cli(
        [
            "screw",
            "predict",
            str(model_file),
            "--data",
            str(DATA / "screw_C.csv"),
            "--json",
            "-",
            "--out",
            str(tmp_path),
        ],
        capsys,
    )
    assert status == 0, err
    result = json.loads(out)
    assert result["source"] == "screw_C" and result["reidentified"] is True
    assert result["paper"]["paper_source"] == "C"
    assert len(result["predicted_error_um"]) == len(result["time_s"]) == 1441
    assert result["metrics"]["max_um"] < result["paper"]["max_um_scaled"]
    assert "max temperature error" in err
    assert (tmp_path / "screw_rises_screw_C.png").is_file() and (tmp_path / "screw_error_screw_C.png").is_file()


def test_the_papers_line_law_on_request(tmp_path, capsys):
    """--alpha-law line: α′ = a0 + a1·τ0, read from the rise at the source, as printed in the paper."""
    args = ["screw", "compare", str(DATA / "screw_H.csv"), "--validate", str(DATA / "screw_B.csv"), "--json", "-"]
    status, out, err = run_cli([*args, "--out", str(tmp_path / "line"), "--alpha-law", "line"], capsys)
    assert status == 0, err
    assert "straight line in τ0" in err
    line = json.loads(out)
    status, out, err = run_cli([*args, "--out", str(tmp_path / "table")], capsys)
    table = json.loads(out)
    assert (line["alpha_prime"]["used"], table["alpha_prime"]["used"]) == ("line", "table")
    assert line["alpha_prime"]["a0_m2_s"] == pytest.approx(table["alpha_prime"]["a0_m2_s"])

    def worst(result):
        return next(r["max_temp_K"] for r in result["rows"] if r["run"] == "screw_B" and r["model"] == "screw")

    assert worst(line) > worst(table)
    saved = json.loads((tmp_path / "line" / "screw_model.json").read_text())
    assert saved["settings"]["alpha_law"] == "line"


def test_predict_uses_a_stored_source_and_gives_the_field_anywhere(model_file, tmp_path, capsys):
    args = ["screw", "predict", str(model_file), "--data", str(DATA / "screw_A.csv"), "--at", "0.16,0.25"]
    status, out, _ = run_cli([*args, "--json", str(tmp_path / "p.json")], capsys)
    assert status == 0 and "from the model" in out
    assert str(tmp_path / "p.json") in out.splitlines()[-1]  # the wrote line names the file written
    result = json.loads((tmp_path / "p.json").read_text())
    field = result["field"]
    assert field["x_m"] == [0.16, 0.25]
    assert [row[0] for row in field["error_um"]] == pytest.approx(result["predicted_error_um"], abs=1e-9)
    assert field["error_um"][-1][1] > field["error_um"][-1][0] > 0
    assert len(field["rise_K"]) == len(result["time_s"])


def test_compare_rows_for_screw_and_mlr(tmp_path, capsys):
    status, out, err = run_cli(
        [
            "screw",
            "compare",
            str(DATA / "screw_H.csv"),
            "--validate",
            str(DATA / "screw_B.csv"),
            "--json",
            str(tmp_path / "c.json"),
            "--out",
            str(tmp_path),
        ],
        capsys,
    )
    assert status == 0, err
    result = json.loads((tmp_path / "c.json").read_text())
    assert result["runs"] == ["screw_H", "screw_B"]
    assert {(r["model"], r["run"]) for r in result["rows"]} == {
        (m, r) for m in ("screw", "mlr") for r in ("screw_H", "screw_B")
    }
    assert "paper 0.6 + 0.08·τ0" in out


def test_compare_keeps_a_model_identified_from_other_runs(model_file, tmp_path, capsys):
    folder = tmp_path / "out"
    folder.mkdir()
    identified = folder / "screw_model.json"
    identified.write_bytes(model_file.read_bytes())  # identified from screw_H then screw_A
    compare = ["screw", "compare", str(DATA / "screw_A.csv"), "--validate", str(DATA / "screw_H.csv")]
    status, _, err = run_cli([*compare, "--out", str(folder)], capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1
    assert "identified from other runs (screw_A.csv, screw_H.csv)" in err and "--force" in err
    assert identified.read_bytes() == model_file.read_bytes()
    assert sorted(p.name for p in folder.iterdir()) == ["screw_model.json"]  # no figure either
    assert run_cli([*compare, "--out", str(folder), "--force"], capsys)[0] == 0
    runs = json.loads(identified.read_text())["identification"]["runs"]
    assert list(runs) == ["screw_A", "screw_H"]
    assert run_cli([*compare, "--out", str(folder)], capsys)[0] == 0  # its own output, same runs: replaced


def _expect_input_error(args, capsys, folder):
    status, out, err = run_cli(args, capsys)
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("groupfit screw: error:")
    assert not folder.exists() or not any(folder.iterdir())
    return lines[0]


def test_too_few_sensors_is_refused(tmp_path, capsys):
    frame = pd.read_csv(DATA / "screw_H.csv")[["time_s", "T0mm", "T60mm", "T140mm", "error_um", "probe_x_m"]]
    frame.to_csv(tmp_path / "three.csv", index=False)
    out = tmp_path / "out"
    line = _expect_input_error(["screw", "identify", str(tmp_path / "three.csv"), "--out", str(out)], capsys, out)
    assert "3 temperature sensor(s)" in line and "at least 4" in line


def test_run_too_short_to_identify_is_refused(tmp_path, capsys):
    pd.read_csv(DATA / "screw_H.csv").iloc[:181].to_csv(tmp_path / "short.csv", index=False)  # 15 min
    out = tmp_path / "out"
    line = _expect_input_error(["screw", "identify", str(tmp_path / "short.csv"), "--out", str(out)], capsys, out)
    assert "steady" in line


def test_new_source_shorter_than_t_r_is_refused(tmp_path, capsys):
    pd.read_csv(DATA / "screw_B.csv").iloc[:40].to_csv(tmp_path / "brief.csv", index=False)  # 195 s
    out = tmp_path / "out"
    line = _expect_input_error(
        ["screw", "identify", str(DATA / "screw_H.csv"), str(tmp_path / "brief.csv"), "--out", str(out)], capsys, out
    )
    assert "first 400 s" in line


def test_a_run_without_position_named_sensors_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    line = _expect_input_error(["screw", "identify", str(DATA / "paper_cycle.csv"), "--out", str(out)], capsys, out)
    assert "T<mm>mm" in line


@pytest.mark.parametrize("renamed", ["T140 mm", "T140mm_x", "t140_mm"])
def test_a_sensor_named_almost_as_one_is_named_in_a_note(tmp_path, capsys, renamed):
    """A column that reads as a sensor's position without the T<mm>mm form is not read as a sensor, and the
    report says so: the identification then runs on the other sensors, as on the run without that column."""
    frame = pd.read_csv(DATA / "screw_H.csv")
    frame.rename(columns={"T140mm": renamed}).to_csv(tmp_path / "renamed.csv", index=False)
    frame.drop(columns="T140mm").to_csv(tmp_path / "dropped.csv", index=False)
    reports = {}
    for name in ("renamed", "dropped"):
        status, out, err = run_cli(
            ["screw", "identify", str(tmp_path / f"{name}.csv"), "--out", str(tmp_path / name)], capsys
        )
        assert status == 0
        reports[name] = out + err
    assert f"'{renamed}' read as no sensor: a sensor's column is named T<mm>mm" in reports["renamed"]
    assert "read as no sensor" not in reports["dropped"]
    identified = {name: json.loads((tmp_path / name / "screw_model.json").read_text()) for name in reports}
    assert identified["renamed"]["h_W_m2K"] == identified["dropped"]["h_W_m2K"]


def test_predict_refuses_a_grouped_model_file(tmp_path, capsys):
    (tmp_path / "m.json").write_text(json.dumps({"format": "groupfit-model/1"}))
    line = _expect_input_error(
        ["screw", "predict", str(tmp_path / "m.json"), "--data", str(DATA / "screw_A.csv")], capsys, tmp_path / "x"
    )
    assert "ball-screw model" in line


def test_a_moving_nut_run_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    line = _expect_input_error(["screw", "identify", str(DATA / "screw_nut.csv"), "--out", str(out)], capsys, out)
    assert "nut_x_m" in line


def test_predict_on_a_run_without_the_probe_says_so_instead_of_a_nan(model_file, tmp_path, capsys):
    run = pd.read_csv(DATA / "screw_A.csv").drop(columns="probe_x_m")
    run.to_csv(tmp_path / "no_probe.csv", index=False)
    status, out, err = run_cli(["screw", "predict", str(model_file), "--data", str(tmp_path / "no_probe.csv")], capsys)
    assert status == 0, err
    assert "no error at the probe (the run has no 'probe_x_m' column" in out and "nan" not in out


def test_the_plausible_ranges_are_the_screw_verbs_options(model_file, tmp_path, capsys):
    """A reading beyond the default plausible range is refused naming an option the screw verb has, and that
    option widens the range (the prediction then the same as on the run without the outlier's row)."""
    run = pd.read_csv(DATA / "screw_A.csv")
    run.loc[10, "T20mm"] = 600.0
    run.to_csv(tmp_path / "hot.csv", index=False)
    line = _expect_input_error(
        ["screw", "predict", str(model_file), "--data", str(tmp_path / "hot.csv"), "--out", str(tmp_path / "a")],
        capsys,
        tmp_path / "a",
    )
    assert "row 11, column 'T20mm': 600 °C is outside the plausible range -50…500 °C" in line
    assert "--range-temp=LOW,HIGH" in line
    wide = ["--data", str(tmp_path / "hot.csv"), "--range-temp=-50,700", "--json", str(tmp_path / "p.json")]
    status, out, err = run_cli(["screw", "predict", str(model_file), *wide], capsys)
    assert status == 0, err
    run.loc[10, "error_um"] = 2e5
    run.loc[10, "T20mm"] = 20.0
    run.to_csv(tmp_path / "far.csv", index=False)
    args = ["screw", "identify", str(DATA / "screw_H.csv"), str(tmp_path / "far.csv"), "--out", str(tmp_path / "b")]
    assert "--range-error MAX" in _expect_input_error(args, capsys, tmp_path / "b")
    status, out, err = run_cli([*args, "--range-error", "1e6"], capsys)
    assert status == 0, err


def test_a_field_position_off_the_screw_is_refused_as_a_probe_position_is(model_file, tmp_path, capsys):
    """--at beyond twice the furthest sensor gave overflow warnings and a field of nulls; now one line."""
    args = ["screw", "predict", str(model_file), "--data", str(DATA / "screw_A.csv"), "--out", str(tmp_path / "o")]
    line = _expect_input_error([*args, "--at", "0.1,5"], capsys, tmp_path / "o")
    assert "--at '0.1,5': 5 m is off the screw (x from the source, 0…0.28 m" in line
    status, out, err = run_cli([*args, "--at", "0.1,0.28", "--json", str(tmp_path / "p.json")], capsys)
    assert status == 0 and "Warning" not in err, err
    field = json.loads((tmp_path / "p.json").read_text())["field"]
    assert field["x_m"] == [0.1, 0.28] and all(v is not None for row in field["error_um"] for v in row)


def test_predict_names_the_missing_error_column_and_reads_the_one_error_names(model_file, tmp_path, capsys):
    frame = pd.read_csv(DATA / "screw_A.csv")
    frame.rename(columns={"error_um": "disp_um"}).to_csv(tmp_path / "disp.csv", index=False)
    frame.assign(error_mm=frame["error_um"] / 1000).drop(columns="error_um").to_csv(tmp_path / "mm.csv", index=False)
    predict = ["screw", "predict", str(model_file), "--source", "screw_A", "--json", "-"]
    status, out, err = run_cli([*predict, "--data", str(DATA / "screw_A.csv")], capsys)
    reference = json.loads(out)["metrics"]
    status, out, err = run_cli([*predict, "--data", str(tmp_path / "disp.csv")], capsys)
    assert status == 0 and "the run has no 'error_um' column; name it with --error" in err
    assert "probe_x_m" not in err
    for data, column in (("disp.csv", "disp_um"), ("mm.csv", "error_mm")):
        status, out, err = run_cli([*predict, "--data", str(tmp_path / data), "--error", column], capsys)
        assert status == 0, err
        metrics = json.loads(out)["metrics"]
        assert metrics["max_um"] == pytest.approx(reference["max_um"], rel=1e-12)
        assert metrics["rms_um"] == pytest.approx(reference["rms_um"], rel=1e-12)
    status, out, err = run_cli([*predict, "--data", str(tmp_path / "disp.csv"), "--error", "nope"], capsys)
    assert status == 2 and "--error 'nope': no such column" in err and len(err.strip().splitlines()) == 1


def test_predict_without_the_sensor_at_the_source_labels_what_it_used(model_file, tmp_path, capsys):
    frame = pd.read_csv(DATA / "screw_A.csv").drop(columns="T0mm")
    frame.to_csv(tmp_path / "no0.csv", index=False)
    args = ["screw", "predict", str(model_file), "--data", str(tmp_path / "no0.csv"), "--source", "screw_A"]
    status, out, err = run_cli([*args, "--json", str(tmp_path / "p.json")], capsys)
    assert status == 0, err
    result = json.loads((tmp_path / "p.json").read_text())
    assert "max temperature error (4/8/12 cm)" in out and "0/4/8/12" not in out
    assert "no sensor at the source" in out and "T20mm" in out
    assert any("T20mm" in note for note in result["notes"])
    columns = [result["positions_m"].index(x) for x in (0.04, 0.08, 0.12)]
    measured = pd.DataFrame(result["measured_rise_K"]).iloc[:, columns]
    predicted = pd.DataFrame(result["predicted_rise_K"]).iloc[:, columns]
    assert result["metrics"]["max_temp_K"] == pytest.approx(float((predicted - measured).abs().max().max()))
    sensors = frame[[f"T{mm}mm" for mm in range(20, 141, 20)]]
    ambient = sensors.iloc[0].mean()
    paper = result["metrics"]["paper"]
    assert paper["rise_sensor"] == "T20mm"
    assert paper["scale"] == pytest.approx((sensors["T20mm"] - ambient).max() / (12.4 + 0.5), rel=1e-12)


def test_a_transient_too_short_for_the_fraction_points_to_the_option_that_widens_it(tmp_path, capsys):
    identify = ["screw", "identify", str(DATA / "screw_H.csv"), "--out", str(tmp_path / "s")]
    status, out, err = run_cli([*identify, "--transient-fraction", "0.01"], capsys)
    assert status == 2 and "raise --transient-fraction (now 0.01, default 0.8)" in err
    assert "alpha_step_s" not in err and len(err.strip().splitlines()) == 1
    status, out, err = run_cli(identify, capsys)
    assert status == 0, err


def test_compare_reads_the_error_column_it_is_given(tmp_path, capsys):
    for name in ("screw_H", "screw_B"):
        frame = pd.read_csv(DATA / f"{name}.csv")
        mm = frame.assign(error_mm=frame["error_um"] / 1000).drop(columns="error_um")
        mm.to_csv(tmp_path / f"{name}.csv", index=False)
    rows = {}
    for folder, error in ((DATA, []), (tmp_path, ["--error", "error_mm"])):
        out = tmp_path / f"out{len(rows)}"
        args = ["screw", "compare", str(folder / "screw_H.csv"), "--validate", str(folder / "screw_B.csv"), *error]
        status, _, err = run_cli([*args, "--json", str(out / "c.json"), "--out", str(out)], capsys)
        assert status == 0, err
        rows[folder] = {(r["model"], r["run"]): r["rms_um"] for r in json.loads((out / "c.json").read_text())["rows"]}
    assert rows[tmp_path] == pytest.approx(rows[DATA], rel=1e-12)
    runs = [str(tmp_path / "screw_H.csv"), "--validate", str(tmp_path / "screw_B.csv")]
    status, _, err = run_cli(["screw", "compare", *runs, "--error", "nope", "--out", str(tmp_path / "no")], capsys)
    assert status == 2 and "column 'nope' not found" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "no").exists()
