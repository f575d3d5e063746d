"""A position model replayed and diagnosed on its table of check runs (several rows per time stamp)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main

POSITIONS = np.arange(0.0, 301.0, 50.0)


def check_run_table(seed: int = 0, n: int = 40, *, t1_rise: float = 5.0, warmer: float = 0.0) -> pd.DataFrame:
    """Check runs every 2 min at 7 positions in a shuffled order: an offset, a slope and a curvature that grow
    with T1 and T2 (T1 rising by ``t1_rise``; ``warmer``: every temperature, the air's too, that much higher)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 120.0
    t1 = 20 + t1_rise * (1 - np.exp(-t / 3000))
    t2 = 20 + 3 * (1 - np.exp(-t / 1500)) + np.sin(t / 2000)
    rows = []
    for i in range(n):
        for p in rng.permutation(POSITIONS):
            d = p - 150
            r1, r2 = t1[i] - 20, t2[i] - 20
            error = 2 * r1 + r2 + (0.01 * r1 + 0.005 * r2) * d + 2e-5 * r1 * d * d + 0.1 * rng.standard_normal()
            rows.append((t[i], p, t1[i] + warmer, t2[i] + warmer, 20.0 + warmer, error))
    return pd.DataFrame(rows, columns=["time_s", "P_mm", "T1", "T2", "T_amb", "error_um"])


@pytest.fixture(scope="module")
def position_model(tmp_path_factory):
    folder = tmp_path_factory.mktemp("position_replay")
    table = check_run_table()
    table.to_csv(folder / "axis.csv", index=False)
    stream = table.assign(time_s=np.arange(len(table)) * 10.0)  # the same rows, one per sample
    stream.to_csv(folder / "stream.csv", index=False)
    fit = ["fit", "--data", str(folder / "axis.csv"), "--temps", "T1,T2", "--position", "P_mm"]
    fit += ["--position-order", "2", "--p", "0", "--out", str(folder / "m"), "--quiet"]
    assert main(fit) == 0
    return folder


def test_replay_scores_every_row_of_a_check_run_table_at_its_own_position(position_model, capsys):
    folder = position_model
    model = str(folder / "m" / "model.json")
    assert main(["replay", model, "--data", str(folder / "axis.csv"), "--json", str(folder / "table.json")]) == 0
    assert main(["replay", model, "--data", str(folder / "stream.csv"), "--json", str(folder / "stream.json")]) == 0
    table = json.loads((folder / "table.json").read_text())
    stream = json.loads((folder / "stream.json").read_text())
    assert table["rows"] == stream["n_samples"] == 7 * 40
    assert table["rms_um"] == pytest.approx(stream["rms_um"], rel=1e-12)
    assert table["max_um"] == pytest.approx(stream["max_um"], rel=1e-12)
    by_row = [s["residual_um"] for s in table["samples"]]
    assert by_row == pytest.approx([s["residual_um"] for s in stream["samples"]], rel=1e-9, abs=1e-12)
    training = json.loads((folder / "m" / "model.json").read_text())["training"]
    assert table["rms_um"] == pytest.approx(training["position_rms_um"], rel=1e-9)
    printed = capsys.readouterr().out
    assert "every row is scored at its own position" in printed
    assert "bursts" not in printed


def test_replay_of_a_check_run_table_refuses_what_only_a_stream_takes(position_model, capsys):
    folder = position_model
    args = ["replay", str(folder / "m" / "model.json"), "--data", str(folder / "axis.csv"), "--probe-every", "600"]
    assert main(args) == 2
    line = capsys.readouterr().err.strip()
    assert "--probe-every" in line and "axis.csv" in line and "\n" not in line


def test_diagnose_refuses_a_position_model_in_one_line_writing_nothing(position_model, capsys):
    folder = position_model
    out, report = folder / "dg", folder / "dg.json"
    args = ["diagnose", str(folder / "m" / "model.json"), "--data", str(folder / "axis.csv")]
    assert main([*args, "--out", str(out), "--json", str(report)]) == 2
    line = capsys.readouterr().err.strip()
    assert "position model" in line and "P_mm" in line and "\n" not in line
    assert not out.exists() and not report.exists()


def test_replay_of_a_stream_with_the_position_in_metres_notes_the_unit_as_fit_does(position_model, capsys):
    folder = position_model
    stream = pd.read_csv(folder / "stream.csv")
    stream.assign(X_m=stream["P_mm"] / 1000).drop(columns="P_mm").to_csv(folder / "stream_m.csv", index=False)
    table = pd.read_csv(folder / "axis.csv")
    table.assign(X_m=table["P_mm"] / 1000).drop(columns="P_mm").to_csv(folder / "axis_m.csv", index=False)
    fit = ["fit", "--data", str(folder / "axis_m.csv"), "--temps", "T1,T2", "--position", "X_m"]
    assert main([*fit, "--position-order", "2", "--p", "0", "--out", str(folder / "m_metres")]) == 0
    fitted = capsys.readouterr().out
    note = "position column 'X_m' is in another unit than mm by its name: read ×1000 as mm"
    assert note in fitted
    model = str(folder / "m_metres" / "model.json")
    assert main(["replay", model, "--data", str(folder / "stream_m.csv"), "--json", str(folder / "m.json")]) == 0
    assert f"stream_m.csv: {note}" in capsys.readouterr().out
    metres = json.loads((folder / "m.json").read_text())
    assert any(note in line for line in metres["data_notes"])
    millimetres = json.loads((folder / "stream.json").read_text())  # the model fitted in mm, on the same rows
    assert metres["rms_um"] == pytest.approx(millimetres["rms_um"], rel=1e-9)


def test_fit_with_a_dead_band_reports_the_figures_replay_gives_and_says_the_others_are_without_it(
    position_model, capsys
):
    folder = position_model
    fit = ["fit", "--data", str(folder / "axis.csv"), "--temps", "T1,T2", "--position", "P_mm", "--p", "0"]
    fit += ["--position-order", "2", "--dead-band", "1", "--dead-band-ref", "T_amb", "--out", str(folder / "band")]
    assert main([*fit, "--json", str(folder / "band.json")]) == 0
    printed = capsys.readouterr().out
    line = next(text for text in printed.splitlines() if text.startswith("dead band 1 degC against T_amb"))
    assert "in the model" in line and "the figures above are of the model without it" in line
    training = json.loads((folder / "band.json").read_text())["training"]
    model = str(folder / "band" / "model.json")
    replay = ["replay", model, "--data", str(folder / "stream.csv")]
    assert main([*replay, "--json", str(folder / "band_stream.json")]) == 0
    stream = json.loads((folder / "band_stream.json").read_text())
    assert training["dead_band_rms_um"] == pytest.approx(stream["rms_um"], rel=1e-9)
    assert training["dead_band_max_um"] == pytest.approx(stream["max_um"], rel=1e-9)
    assert training["dead_band_rms_um"] > 1.5 * training["position_rms_um"]  # the band holds the compensation
    assert f"RMS {training['dead_band_rms_um']:.3g} um" in line


def wide_table(table: pd.DataFrame, error: str = "error_um") -> pd.DataFrame:
    """The long table as a wide one: one row per check run, one ``err_P<mm>`` column per position."""
    errors = table.pivot(index="time_s", columns="P_mm", values=error)
    errors.columns = [f"err_P{p:04.0f}" for p in errors.columns]
    return table.groupby("time_s")[["T1", "T2", "T_amb"]].first().join(errors).reset_index()


def fitted(folder, data: str, name: str, *extra: str) -> dict:
    """The model ``fit --position P_mm`` writes for ``data`` (order 2, --p 0)."""
    fit = ["fit", "--data", str(folder / data), "--temps", "T1,T2", "--position", "P_mm", "--position-order", "2"]
    assert main([*fit, "--p", "0", *extra, "--out", str(folder / name), "--quiet"]) == 0
    return json.loads((folder / name / "model.json").read_text())


def replayed(folder, model: str, data: str, *extra: str) -> dict:
    """``replay --json`` of ``model`` (a folder under ``folder``) on ``data``."""
    report = folder / f"{model}_{data}.json"
    assert (
        main(
            ["replay", str(folder / model / "model.json"), "--data", str(folder / data), *extra, "--json", str(report)]
        )
        == 0
    )
    return json.loads(report.read_text())


def same_model(a: dict, b: dict) -> None:
    """Two model files with the same coefficients and residual figures, within 1e-9 relative."""
    assert np.ravel(a["coefficients"]) == pytest.approx(np.ravel(b["coefficients"]), rel=1e-9)
    position_a, position_b = a["position"]["coefficients"], b["position"]["coefficients"]
    assert np.ravel(position_a) == pytest.approx(np.ravel(position_b), rel=1e-9)
    for key in ("position_rms_um", "position_max_um"):
        assert a["training"][key] == pytest.approx(b["training"][key], rel=1e-9)


def scaled_tables(folder: Path, shape: str, name: str, column: str, divisor: float) -> tuple[str, str]:
    """The table of check runs (``long``: the fixture's ``axis.csv``; ``wide``: one error column per position)
    and the same with its error divided by ``divisor`` (``long``: under ``column``), written in ``folder``; the
    two file names."""
    table = check_run_table()
    if shape == "wide":
        wide = wide_table(table)
        wide.to_csv(folder / "wide_um.csv", index=False)
        errors = [c for c in wide.columns if c.startswith("err_P")]
        wide.assign(**{c: wide[c] / divisor for c in errors}).to_csv(folder / f"wide_{name}.csv", index=False)
        return "wide_um.csv", f"wide_{name}.csv"
    scaled = table.assign(**{column: table["error_um"] / divisor}).drop(columns="error_um")
    scaled.to_csv(folder / f"axis_{name}.csv", index=False)
    return "axis.csv", f"axis_{name}.csv"


@pytest.mark.parametrize("shape", ["long", "wide"])
def test_a_table_with_its_error_in_mm_is_fitted_and_replayed_in_um(position_model, shape):
    folder = position_model
    um, mm = scaled_tables(folder, shape, "mm", "error_mm", 1000)
    truth = fitted(folder, um, f"{shape}_um")
    model = fitted(folder, mm, f"{shape}_mm", "--error", "error_mm")
    same_model(model, truth)
    assert truth["training"]["position_rms_um"] > 0.1  # µm, not mm
    scored = replayed(folder, f"{shape}_um", mm, "--error", "error_mm")
    expected = replayed(folder, f"{shape}_um", um)
    by_row = [s["residual_um"] for s in scored["samples"]]
    assert by_row == pytest.approx([s["residual_um"] for s in expected["samples"]], rel=1e-9, abs=1e-12)
    assert scored["rms_um"] == pytest.approx(truth["training"]["position_rms_um"], rel=1e-9)


@pytest.mark.parametrize("shape", ["long", "wide"])
def test_error_column_times_k_reads_a_table_of_check_runs_as_a_stream(position_model, shape, capsys):
    folder = position_model
    um, half = scaled_tables(folder, shape, "half", "e_half", 2)
    truth = fitted(folder, um, f"{shape}_um")
    model = fitted(folder, half, f"{shape}_half", "--error", "e_half*2")
    same_model(model, truth)
    assert model["error"] == "e_half*2"
    capsys.readouterr()
    scored = replayed(folder, f"{shape}_half", half)  # the model's own error, read ×2
    assert "read ×2 as µm" in capsys.readouterr().out
    expected = replayed(folder, f"{shape}_um", um)
    by_row = [s["residual_um"] for s in scored["samples"]]
    assert by_row == pytest.approx([s["residual_um"] for s in expected["samples"]], rel=1e-9, abs=1e-12)
    again = replayed(folder, f"{shape}_um", half, "--error", "e_half*2")
    assert again["rms_um"] == pytest.approx(expected["rms_um"], rel=1e-9)


def as_stream(table: pd.DataFrame) -> pd.DataFrame:
    """The same rows, one per sample (10 s apart)."""
    return table.assign(time_s=np.arange(len(table)) * 10.0)


def table_and_stream(folder, capsys, name: str, table: pd.DataFrame) -> tuple[dict, dict, str]:
    """``replay --json`` of the fixture's model on ``table`` and on the same rows as a stream, and what the
    table's replay printed."""
    model = str(folder / "m" / "model.json")
    reports = []
    for data in (name, f"{name}_stream"):
        (table if data == name else as_stream(table)).to_csv(folder / f"{data}.csv", index=False)
        capsys.readouterr()
        assert (
            main(["replay", model, "--data", str(folder / f"{data}.csv"), "--json", str(folder / f"{data}.json")]) == 0
        )
        reports.append((json.loads((folder / f"{data}.json").read_text()), capsys.readouterr().out))
    return reports[0][0], reports[1][0], reports[0][1]


@pytest.mark.parametrize(
    "name, table, moved",
    [
        ("hotter", check_run_table(1, n=50, t1_rise=7.0), "T1"),
        ("warm_day", check_run_table(0, warmer=3.0), "T_amb"),
    ],
)
def test_a_table_beyond_the_modelling_range_is_named_as_on_a_stream(position_model, capsys, name, table, moved):
    scored, stream, printed = table_and_stream(position_model, capsys, name, table)
    assert [b["input"] for b in scored["beyond_modelling_range"]] == [moved]
    assert scored["beyond_modelling_range"] == stream["beyond_modelling_range"]
    assert (moved == "T_amb") == bool(scored["beyond_modelling_range"][0].get("reference"))
    note = next(n for n in stream["notes"] if "leaves the modelling range" in n)
    assert note in scored["notes"] and f"note     {note}" in printed


def beyond_the_travel() -> pd.DataFrame:
    table = check_run_table()
    return table.assign(P_mm=table["P_mm"].replace(300.0, 450.0))


def held_air() -> pd.DataFrame:
    table = check_run_table(1, n=50)
    table.loc[70, "T_amb"] = np.nan  # the first row of check run 11
    return table


def held_later_in_a_check_run() -> pd.DataFrame:
    table = check_run_table(1, n=50)
    table.loc[71, "T1"] = np.nan  # the second row of check run 11: its position's reading there is held
    return table


@pytest.mark.parametrize(
    "name, table",
    [("beyond_travel", beyond_the_travel()), ("held_air", held_air()), ("held_later", held_later_in_a_check_run())],
)
def test_a_table_counts_the_rows_held_or_clamped_to_the_travel_as_a_stream_counts_its_samples(
    position_model, capsys, name, table
):
    scored, stream, printed = table_and_stream(position_model, capsys, name, table)
    faults = {key.replace("_rows", ""): n for key, n in scored["faults"].items()}
    assert faults == {key.replace("_samples", ""): n for key, n in stream["faults"].items()}
    assert faults["position_clamped"] + faults["held"] > 0
    assert scored.get("readings_out_of_range") == stream.get("readings_out_of_range")
    line = next(text for text in printed.splitlines() if text.startswith("faults"))
    assert f"{faults['held']} row(s) on held readings" in line
    assert f"{faults['position_clamped']} at a position clamped to the travel" in line
    if name != "held_later":  # held there: the stream holds the row before, the table the check run before
        assert scored["rms_um"] == pytest.approx(stream["rms_um"], rel=1e-9)


def test_range_error_on_a_table_leaves_the_rows_beyond_it_out_of_the_score_as_a_stream(position_model, capsys):
    folder = position_model
    table = check_run_table(1, n=50, t1_rise=7.0)
    table.to_csv(folder / "large.csv", index=False)
    as_stream(table).to_csv(folder / "large_stream.csv", index=False)
    model = str(folder / "m" / "model.json")
    reports = {}
    for data in ("large", "large_stream"):
        capsys.readouterr()
        args = ["replay", model, "--data", str(folder / f"{data}.csv"), "--range-error", "5"]
        assert main([*args, "--json", str(folder / f"{data}_5.json")]) == 0
        reports[data] = json.loads((folder / f"{data}_5.json").read_text()), capsys.readouterr().out
    (scored, printed), (stream, _) = reports["large"], reports["large_stream"]
    beyond = int(np.sum(np.abs(table["error_um"]) > 5))
    assert 0 < beyond < len(table)
    assert scored["scored_samples"] == stream["scored_samples"] == len(table) - beyond
    assert scored["measured_samples"] == stream["measured_samples"]
    assert scored["rms_um"] == pytest.approx(stream["rms_um"], rel=1e-9)
    note = next(n for n in stream["data_notes"] if "beyond ±5 µm" in n).split("large_stream.csv: ")[1]
    assert f"{folder / 'large.csv'}: {note}" in scored["notes"] and note in printed


def test_a_wide_table_of_one_position_is_refused_naming_its_error_columns(position_model, capsys):
    folder = position_model
    one = wide_table(check_run_table())[["time_s", "T1", "T2", "T_amb", "err_P0100"]]
    one.to_csv(folder / "wide_one.csv", index=False)
    assert main(["replay", str(folder / "m" / "model.json"), "--data", str(folder / "wide_one.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "err_P<mm>" in err and "one position only" in err and "P_mm" not in err and len(err.splitlines()) == 1


def test_a_grouped_model_on_a_table_at_another_period_is_refused_without_pointing_to_resample(position_model, capsys):
    folder = position_model
    grouped = fitted(folder, "axis.csv", "grouped", "--p", "1")
    assert grouped["breaks"] and grouped["sampling_period_s"] == 120.0
    faster = check_run_table().assign(time_s=lambda t: t["time_s"] / 2)  # check runs every 60 s
    faster.to_csv(folder / "axis_60s.csv", index=False)
    assert main(["replay", str(folder / "grouped" / "model.json"), "--data", str(folder / "axis_60s.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "check runs every 60 s, the model's period is 120 s" in err and "--resample" not in err
    assert len(err.splitlines()) == 1


def test_an_empty_input_on_a_check_runs_first_row_is_named_by_its_row_in_the_file(position_model, capsys):
    folder = position_model
    table = check_run_table()
    table.loc[70, "T1"] = np.nan  # the first of the eleventh check run's seven rows
    table.to_csv(folder / "nan_t1.csv", index=False)
    fit = ["fit", "--data", str(folder / "nan_t1.csv"), "--temps", "T1,T2", "--position", "P_mm"]
    replay = ["replay", str(folder / "m" / "model.json"), "--data", str(folder / "nan_t1.csv")]
    for args in ([*fit, "--out", str(folder / "never")], replay):
        capsys.readouterr()
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert "nan_t1.csv: row 71, column 'T1' is empty" in err and "--resample" not in err
        assert len(err.splitlines()) == 1
    assert not (folder / "never").exists()
