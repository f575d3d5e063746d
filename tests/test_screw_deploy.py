"""The ball-screw model deployed: replay against the offline model, C bit for bit against the replay, refusals."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.screw.deploy import FAULT_READING, ScrewLaw
from groupfit.screw.modelfile import load_model
from groupfit.screw.runs import load_screw_run

DATA = Path(__file__).resolve().parents[1] / "datasets"

DRIVER = r"""#include <stdio.h>
#include <stdlib.h>
#include "groupfit_screw.h"
int main(void)
{
    double t, x, tau0, e;
    while (scanf("%lf %lf %lf", &t, &x, &tau0) == 3) {
        int code = gfs_error_um(t, x, tau0, &e);
        printf("%d %a\n", code, e);
    }
    return 0;
}
"""


@pytest.fixture(scope="module", params=["table", "line"])
def model_path(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(f"screw_{request.param}")
    args = ["screw", "identify", str(DATA / "screw_H.csv"), str(DATA / "screw_A.csv"), "--out", str(out)]
    assert main([*args, "--alpha-law", request.param]) == 0
    return out / "screw_model.json"


def readings(law: ScrewLaw, model_path) -> np.ndarray:
    """(time, x, τ0) of run H with the probe anywhere on the screw, and unusable and edge samples."""
    run = load_screw_run(DATA / "screw_H.csv")
    rng = np.random.default_rng(0)
    x = rng.uniform(0.0, 0.3, len(run.time))
    tau0 = load_model(model_path).reference_rise(run.rises, run.positions)
    rows = np.column_stack([run.time, x, tau0])
    edges = [[0.0, 0.1, 1.0], [-5.0, 0.1, 1.0], [1e7, 0.2, 5.0], [100.0, 0.0, 1.0], [2.0, 0.15, 0.5]]
    faults = [[np.nan, 0.1, 1.0], [100.0, -0.01, 1.0], [100.0, np.inf, 1.0], [100.0, 0.1, np.nan]]
    return np.vstack([rows, edges, faults])


def test_the_run_time_law_is_the_offline_model(model_path):
    model = load_model(model_path)
    law = ScrewLaw.from_model(model, "screw_A")
    run = load_screw_run(DATA / "screw_A.csv")
    tau0 = model.law_input(run.rises, run.positions)
    offline = model.predict_error(run.time, run.probe_x, tau0, "screw_A")
    codes, replayed = law.replay(run.time, run.probe_x, tau0)
    assert not codes.any()
    assert np.max(np.abs(replayed - offline)) <= 1e-9 * np.max(np.abs(offline))


def test_unusable_readings_are_a_fault_and_no_value(model_path):
    law = ScrewLaw.from_model(load_model(model_path), "screw_H")
    assert law.step(float("nan"), 0.1, 1.0) == (FAULT_READING, 0.0)
    assert law.step(100.0, -0.01, 1.0) == (FAULT_READING, 0.0)
    assert law.step(0.0, 0.1, 1.0) == (0, 0.0)
    assert (law.step(100.0, 0.1, float("nan"))[0] == FAULT_READING) == (law.law == "line")


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
@pytest.mark.toolchain
def test_the_c_export_equals_the_replay_bit_for_bit(model_path, tmp_path):
    assert main(["export", str(model_path), "--target", "c", "--source", "screw_H", "--out", str(tmp_path)]) == 0
    (tmp_path / "driver.c").write_text(DRIVER)
    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2"]
    exe = tmp_path / "driver"
    subprocess.run(
        ["gcc", *flags, "-o", str(exe), str(tmp_path / "groupfit_screw.c"), str(tmp_path / "driver.c"), "-lm"],
        check=True,
    )
    rows = readings(ScrewLaw.from_model(load_model(model_path), "screw_H"), model_path)
    text = "\n".join(" ".join(float(v).hex() if math.isfinite(v) else str(v) for v in row) for row in rows) + "\n"
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stdout.split("\n")
    law = ScrewLaw.from_model(load_model(model_path), "screw_H")
    for row, line in zip(rows, out):
        code, value = line.split()
        assert (int(code), float.fromhex(value)) == law.step(*map(float, row)), row
    assert len([line for line in out if line]) == len(rows)


def test_the_json_export_holds_the_law(model_path, tmp_path):
    assert main(["export", str(model_path), "--target", "json", "--source", "screw_A", "--out", str(tmp_path)]) == 0
    table = json.loads((tmp_path / "groupfit_screw_runtime.json").read_text())
    law = ScrewLaw.from_model(load_model(model_path), "screw_A")
    assert table["format"] == "groupfit-ballscrew-runtime/1" and table["source"] == "screw_A"
    assert (table["C1_K"], table["C2_K"], table["lambda_1_m"]) == (law.c1, law.c2, law.lam)
    assert len(table["quadrature"]["u"]) == 256 and sum(table["quadrature"]["w"]) == pytest.approx(1.0, abs=1e-14)


def test_replay_cli_scores_the_law_on_a_run(model_path, tmp_path, capsys):
    args = ["replay", str(model_path), "--data", str(DATA / "screw_A.csv"), "--source", "screw_A", "--json", "-"]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    model = load_model(model_path)
    run = load_screw_run(DATA / "screw_A.csv")
    offline = model.predict_error(run.time, run.probe_x, model.law_input(run.rises, run.positions), "screw_A")
    replayed = np.array([s["prediction_um"] for s in result["samples"]])
    assert np.allclose(replayed, offline, rtol=1e-9, atol=0)
    assert result["rms_um"] == pytest.approx(float(np.sqrt(np.mean((run.error - offline) ** 2))), rel=1e-9)
    assert all(s["group"] == 1 and s["fault"] == s["code"] == 0 for s in result["samples"])  # the keys of a replay
    residual = np.array([s["residual_um"] for s in result["samples"]])
    assert np.allclose(residual, run.error - replayed, rtol=0, atol=1e-9)


def test_replay_leaves_an_overflowed_error_out_of_the_score_and_honours_range_temp(model_path, tmp_path, capsys):
    """As the grouped replay: an error beyond --range-error is not measured (the RMS over the other samples);
    a temperature beyond --range-temp is refused, and --range-temp widens it."""
    frame = pd.read_csv(DATA / "screw_A.csv")
    frame.loc[[5, 300], "error_um"] = 3e38
    frame.to_csv(tmp_path / "overflow.csv", index=False)
    args = ["replay", str(model_path), "--data", str(tmp_path / "overflow.csv"), "--source", "screw_A", "--json", "-"]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    residual = np.array([s["residual_um"] for s in result["samples"]], dtype=float)
    assert result["scored_samples"] == len(frame) - 2 and np.isnan(residual[[5, 300]]).all()
    kept = np.isfinite(residual)
    assert result["rms_um"] == pytest.approx(float(np.sqrt(np.mean(residual[kept] ** 2))), rel=1e-12)
    frame.loc[7, "T40mm"] = 800.0
    frame.to_csv(tmp_path / "hot.csv", index=False)
    hot = ["replay", str(model_path), "--data", str(tmp_path / "hot.csv"), "--source", "screw_A"]
    assert main(hot) == 2
    assert "800 °C is outside the plausible range -50…500 °C" in capsys.readouterr().err
    assert main([*hot, "--range-temp=-50,900"]) == 0


def test_replay_reads_the_error_and_time_columns_it_is_given(model_path, tmp_path, capsys):
    """--error and --time name the columns as for a grouped model: a renamed error column in mm by its name, read
    ×1000, scores as error_um does; a column asked for and not in the run is refused naming it."""
    frame = pd.read_csv(DATA / "screw_A.csv")
    renamed = frame.assign(error_mm=frame["error_um"] / 1000.0, clock=frame["time_s"]).drop(
        columns=["error_um", "time_s"]
    )
    renamed.to_csv(tmp_path / "renamed.csv", index=False)
    base = ["replay", str(model_path), "--source", "screw_A", "--json", "-"]
    assert main([*base, "--data", str(DATA / "screw_A.csv")]) == 0
    reference = json.loads(capsys.readouterr().out)
    assert main([*base, "--data", str(tmp_path / "renamed.csv"), "--error", "error_mm", "--time", "clock"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["rms_um"] == pytest.approx(reference["rms_um"], rel=1e-12)
    assert main([*base, "--data", str(DATA / "screw_A.csv"), "--error", "error_um*2"]) == 2
    assert "--error 'error_um*2'" in capsys.readouterr().err
    for option, column in (("--error", "nosuchcolumn"), ("--time", "nosuchcolumn")):
        assert main([*base, "--data", str(DATA / "screw_A.csv"), option, column]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "'nosuchcolumn'" in err[0] and "error_um" in err[0]


@pytest.mark.parametrize(
    "args, message",
    [
        (["export", "--target", "st"], "has no error function (erfc)"),
        (["export", "--target", "cec"], "a CEC table is one curve over the position"),
        (["export", "--target", "c"], "the model has the heat sources screw_H, screw_A; choose one with --source"),
        (["export", "--target", "c", "--source", "B"], "--source B: not in"),
        (["replay", "--data", str(DATA / "screw_H.csv"), "--precision", "single"], "double precision only"),
    ],
)
def test_what_cannot_be_deployed_is_refused_with_one_line(model_path, tmp_path, capsys, args, message):
    verb, *rest = args
    assert main([verb, str(model_path), *rest, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not (tmp_path / "out").exists()
