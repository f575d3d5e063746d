"""The deployable AR(1) model: fit options, model file, replay and the C / ST / JSON routines."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.ar1.export import json_table, render
from groupfit.ar1.fitting import fit_ar1_file
from groupfit.ar1.modelfile import AR1File
from groupfit.ar1.rule import AR1Rule
from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.export import write
from groupfit.export.harness import STRICT_FLAGS
from groupfit.models.ar1 import AR1Model

ROOT = Path(__file__).resolve().parents[1]
ROD = ROOT / "datasets" / "rod_ar1.csv"
ROD_CONFIG = ROOT / "configs" / "rod_ar1.toml"


def simulated_process(*, noise: float = 0.0, seed: int = 0, n: int = 900):
    """An exact AR(1) process E(k) = 0.98 E(k-1) + C2(q_k) from E(0) = 0, observed with white noise."""
    rng = np.random.default_rng(seed)
    heat = np.repeat(rng.choice([0.0, 1000.0, 2000.0], size=n // 30), 30)
    c2 = {0.0: 0.0, 1000.0: 0.05, 2000.0: 0.16}
    true = np.zeros(len(heat))
    for k in range(1, len(heat)):
        true[k] = 0.98 * true[k - 1] + c2[heat[k]]
    return heat, true + noise * rng.standard_normal(len(heat)), true


def write_run(path: Path, heat, error, period: float = 15.0) -> Path:
    pd.DataFrame({"time_s": np.arange(len(heat)) * period, "speed_rpm": heat, "error_um": error}).to_csv(
        path, index=False
    )
    return path


# ------------------------------------------------------------------ fitting


def test_closed_form_and_least_squares_agree_on_the_rod_as_documented(tmp_path):
    """docs/fe_model.md: C1 0.990917 (fit) against 0.990903 (closed form); the paper's C2 0.1985 / 0.2977 µm."""
    for extra, name in (([], "fit"), (["--closed-form", str(ROD_CONFIG)], "closed")):
        status = main(
            ["fit", "--model", "ar1", "--data", str(ROD), "--heat", "q_W_m2", "--heat-exponent", "1", "--quiet"]
            + ["--out", str(tmp_path / name), "--json", str(tmp_path / f"{name}.json")]
            + extra
        )
        assert status == 0
    fitted = json.loads((tmp_path / "fit.json").read_text())
    closed = json.loads((tmp_path / "closed.json").read_text())
    assert closed["fit"] == "closed_form" and fitted["fit"] == "one_step"
    assert round(fitted["c1"], 6) == 0.990917 and round(closed["c1"], 6) == 0.990903
    assert closed["c2_um"] == pytest.approx([0.1985, 0.2977], abs=5e-5)
    assert fitted["c2_um"] == pytest.approx(closed["c2_um"], rel=2e-3)
    assert closed["scores"]["closed_form"]["least_squares"]["C1"] == fitted["c1"]


def test_free_run_fit_beats_the_one_step_fit_on_a_noisy_observation():
    """Measurement noise biases the one-step regression (errors in variables); the free-run fit is not."""
    heat, observed, true = simulated_process(noise=0.3, seed=3)
    one = AR1Model(fit_method="one_step", start="zero").fit(heat[:, None], observed)
    free = AR1Model(fit_method="free_run", start="zero").fit(heat[:, None], observed)
    assert abs(free.c1_ - 0.98) < abs(one.c1_ - 0.98)
    assert abs(free.c1_ - 0.98) < 2e-3
    rms = lambda m: float(np.sqrt(np.mean(m.residuals_**2)))  # noqa: E731
    assert rms(free) < rms(one)
    # the free-run optimum: no small change of one coefficient lowers the free-run error
    base = np.sum(free.residuals_**2)
    for name in ("c1_", 1000.0, 2000.0):
        for delta in (-1e-4, 1e-4):
            probe = AR1Model(start="zero").fit(heat[:, None], observed)
            probe.c1_, probe.c2_ = free.c1_, dict(free.c2_)
            if name == "c1_":
                probe.c1_ += delta
            else:
                probe.c2_[name] += delta
            assert np.sum((observed - probe.predict(heat[:, None], initial_error=0.0)) ** 2) >= base


def test_start_zero_and_measured_differ_only_in_where_the_free_run_starts():
    heat, observed, _ = simulated_process()
    shifted = observed + 2.0
    zero = AR1Model(start="zero").fit(heat[:, None], shifted)
    measured = AR1Model(start="measured").fit(heat[:, None], shifted)
    assert zero.c1_ == measured.c1_  # one-step fit: the start plays no part
    decay = 2.0 * zero.c1_ ** np.arange(len(heat))
    np.testing.assert_allclose(zero.residuals_ - measured.residuals_, decay, atol=1e-9)


def test_period_decimates_the_run_and_must_be_a_whole_multiple(tmp_path, capsys):
    heat, observed, _ = simulated_process(n=1200)
    csv = write_run(tmp_path / "run.csv", heat, observed)
    assert main(["fit", "--model", "ar1", "--data", str(csv), "--heat", "speed_rpm", "--period", "30", "--quiet",
                 "--out", str(tmp_path / "m"), "--json", str(tmp_path / "m.json")]) == 0  # fmt: skip
    model = json.loads((tmp_path / "m.json").read_text())
    direct = AR1Model(start="zero").fit(heat[::2, None], observed[::2])
    assert model["sampling_period_s"] == 30.0 and model["c1"] == direct.c1_
    assert main(["fit", "--model", "ar1", "--data", str(csv), "--heat", "speed_rpm", "--period", "20",
                 "--out", str(tmp_path / "bad")]) == 2  # fmt: skip
    assert "--period 20 s is not a whole multiple of the run's sampling period 15 s" in capsys.readouterr().err
    assert not (tmp_path / "bad" / "model.json").exists()


def test_an_unstable_fit_is_refused_with_what_to_do():
    heat = np.repeat([1000.0, 0.0], 50)
    growing = np.cumsum(np.where(heat > 0, 1.0, 0.5))  # keeps rising at rest: C1 > 1
    with pytest.raises(Exception, match="not below 1.*--period.*free-run"):
        fit_ar1_file(heat, growing, period_s=15.0, heat_name="q", error_name="e", source="run.csv")


# ------------------------------------------------------------------ model file, replay


@pytest.fixture(scope="module")
def model() -> AR1File:
    heat, observed, _ = simulated_process(noise=0.05, seed=1)
    return fit_ar1_file(
        heat, observed, period_s=15.0, heat_name="speed_rpm", error_name="error_um", source="sim.csv"
    ).model


def stream():
    """Fitted levels, zero, unseen levels (between, tied, above, below), and readings that must be held."""
    values = [0.0, 1000.0, 2000.0, 1500.0, 700.0, 2600.0, 1e-3, 1999.9999, 3999.0]
    values += [float("nan"), -1.0, float("inf"), 1e6, 2000.0, 1234.5678] + list(np.linspace(0, 4000, 40))
    return np.array(values)


def test_replay_follows_the_estimator_and_holds_bad_readings(model):
    """On good readings the routine is the estimator's free run (its own C2 rule); a bad reading keeps E."""
    estimator = AR1Model(heat_exponent=model.heat_exponent)
    estimator.c1_, estimator.c2_ = model.c1, dict(zip(model.levels, model.c2_um))
    estimator.structural_gain_ = None
    heat = stream()
    good = np.isfinite(heat) & (heat >= 0) & (heat <= model.heat_max)
    replay = AR1Rule(model).replay(heat, initial_um=0.7)
    expected = estimator.predict(heat[good][:, None], initial_error=0.7)
    np.testing.assert_allclose(replay.prediction_um[good], expected, rtol=1e-13, atol=1e-13)
    held = np.flatnonzero(~good)
    np.testing.assert_array_equal(replay.prediction_um[held], replay.prediction_um[held - 1])
    np.testing.assert_array_equal(replay.fault, (~good).astype(int))


def test_model_file_round_trips_and_bad_files_fail_with_the_file_and_key(model, tmp_path, capsys):
    path = tmp_path / "model.json"
    model.save(path)
    assert AR1File.load(path) == model
    data = json.loads(path.read_text())
    run = write_run(tmp_path / "run.csv", stream()[:5], np.zeros(5))
    for key, value, message in (
        ("c1", 1.01, "c1 = 1.01: a stable AR(1) model has 0 < c1 < 1"),
        ("levels", [2000.0, 1000.0], "strictly increasing"),
        ("start", "warm", "start = 'warm'"),
        ("heat_max", 10.0, "heat_max = 10.0: at least the largest level"),
        ("c2_um", [True, *data["c2_um"][1:]], "c2_um[0] = True: a finite number"),
        ("training", {**(data.get("training") or {}), "recordings": "x"}, "training.recordings = 'x': a list of"),
    ):
        broken = tmp_path / f"{key}.json"
        broken.write_text(json.dumps({**data, key: value}))
        assert main(["replay", str(broken), "--data", str(run)]) == 2
        err = capsys.readouterr().err
        assert str(broken) in err and message in err
        assert main(["export", str(broken), "--target", "c", "--out", str(tmp_path / key)]) == 2
        assert not (tmp_path / key).exists() or not any((tmp_path / key).iterdir())
    no_kind = tmp_path / "no_kind.json"
    no_kind.write_text(json.dumps({key: value for key, value in data.items() if key != "kind"}))
    assert main(["replay", str(no_kind), "--data", str(run)]) == 2
    assert "lacks key 'kind': its c1, levels and c2_um are an AR(1) model's" in capsys.readouterr().err


def test_replay_of_a_finer_run_takes_every_step(model, tmp_path):
    heat, observed, _ = simulated_process(n=600)
    fine = write_run(tmp_path / "fine.csv", np.repeat(heat, 2), np.repeat(observed, 2), period=7.5)
    path = tmp_path / "m.json"
    model.save(path)
    options = ["--json", str(tmp_path / "r.json"), "--out", str(tmp_path / "fig")]
    assert main(["replay", str(path), "--data", str(fine), *options]) == 0
    assert (tmp_path / "fig" / "replay.png").stat().st_size > 10_000
    out = json.loads((tmp_path / "r.json").read_text())
    assert out["decimation"] == 2 and out["start"] == "zero"
    np.testing.assert_array_equal(out["prediction_um"], AR1Rule(model).replay(heat).prediction_um)


def test_replay_scores_the_measured_steps_of_a_run_with_missed_error_readings(model, tmp_path):
    heat, observed, _ = simulated_process(n=300)
    missed = observed.copy()
    missed[[50, 51, 200]] = np.nan
    path = tmp_path / "m.json"
    model.save(path)
    run = write_run(tmp_path / "run.csv", heat, missed)
    assert main(["replay", str(path), "--data", str(run), "--json", str(tmp_path / "r.json")]) == 0
    out = json.loads((tmp_path / "r.json").read_text())
    scored = np.isfinite(missed)
    residual = missed[scored] - AR1Rule(model).replay(heat).prediction_um[scored]
    assert out["scores"]["scored_samples"] == 297
    assert out["rms_um"] == pytest.approx(float(np.sqrt(np.mean(residual**2))), rel=1e-12)


def test_replay_scores_only_the_errors_within_range_error(model, tmp_path, capsys):
    """An overflowed error reading is left out of the score (as the grouped replay does), --range-error widens
    what counts, and a run with no plausible reading is scored not at all rather than as NaN."""
    heat, observed, _ = simulated_process(n=300)
    overflow = observed.copy()
    overflow[[40, 41, 200]] = 3e38
    run = write_run(tmp_path / "run.csv", heat, overflow)
    path = tmp_path / "m.json"
    model.save(path)
    assert main(["replay", str(path), "--data", str(run), "--json", str(tmp_path / "r.json")]) == 0
    scores = json.loads((tmp_path / "r.json").read_text())["scores"]
    kept = np.ones(len(heat), bool)
    kept[[40, 41, 200]] = False
    residual = observed[kept] - AR1Rule(model).replay(heat).prediction_um[kept]
    assert scores["scored_samples"] == kept.sum()
    assert scores["rms_um"] == pytest.approx(float(np.sqrt(np.mean(residual**2))), rel=1e-12)
    replayed = json.loads((tmp_path / "r.json").read_text())  # the samples and rms_um every replay gives
    assert replayed["rms_um"] == scores["rms_um"] and len(replayed["samples"]) == len(heat)
    assert [s["i"] for s in replayed["samples"]] == list(range(1, len(heat) + 1))
    assert {s["group"] for s in replayed["samples"]} == {1} and all(s["fault"] == 0 for s in replayed["samples"])
    given = np.array([np.nan if s["residual_um"] is None else s["residual_um"] for s in replayed["samples"]])
    assert np.isnan(given[~kept]).all() and np.allclose(given[kept], residual, rtol=0, atol=1e-12)
    assert "3 reading(s) of the error beyond ±100000 µm (row 41, 42, 201" in capsys.readouterr().out
    wide = ["--range-error", "1e39", "--json", str(tmp_path / "w.json")]
    assert main(["replay", str(path), "--data", str(run), *wide]) == 0
    assert json.loads((tmp_path / "w.json").read_text())["scores"]["scored_samples"] == len(heat)
    gone = write_run(tmp_path / "gone.csv", heat, np.full(len(heat), 3e38))
    assert main(["replay", str(path), "--data", str(gone), "--json", str(tmp_path / "g.json")]) == 0
    assert "scores" not in json.loads((tmp_path / "g.json").read_text())
    assert "error   none (the run has no measured error" in capsys.readouterr().out
    assert main(["replay", str(path), "--data", str(run), "--range-temp=-10,90"]) == 2
    assert "an AR(1) model reads no temperature; leave it out" in capsys.readouterr().err


@pytest.mark.parametrize(
    "option, message",
    [
        (["--heat", "speed_rpm"], "--heat is an option of --model ar1, not of the grouped model"),
        (["--start", "zero"], "--start is an option of --model ar1"),
        (["--heat-exponent", "1"], "--heat-exponent is an option of --model ar1"),
        (["--closed-form", "rod.toml"], "--closed-form is an option of --model ar1"),
        (["--p", "1", "--choose", "bic"], "--choose: p is given (--p 1), so nothing is chosen"),
        (["--p", "0", "--p-target", "5"], "--p-target: p is given (--p 0)"),
    ],
)
def test_the_grouped_fit_refuses_what_it_would_ignore(tmp_path, capsys, option, message):
    heat, observed, _ = simulated_process(n=300)
    run = write_run(tmp_path / "run.csv", heat, observed)
    assert main(["fit", "--data", str(run), *option, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "option", [["--probe-every", "600"], ["--fresh"], ["--resolution-um", "0.1"], ["--continues", "other.csv"]]
)
def test_replay_refuses_what_the_ar1_routine_does_not_do(model, tmp_path, capsys, option):
    heat, observed, _ = simulated_process(n=300)
    run = write_run(tmp_path / "run.csv", heat, observed)
    write_run(tmp_path / "other.csv", heat, observed)
    path = tmp_path / "m.json"
    model.save(path)
    capsys.readouterr()
    assert main(["replay", str(path), "--data", str(run), *option, "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{option[0]}: an AR(1) model file is replayed without it" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "r.json").exists()


# ------------------------------------------------------------------ C, ST and JSON routines

DRIVER = r"""#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "groupfit_ar1.h"
int main(void)
{
    char line[256];
    gf_ar1_state state;
    gf_ar1_init(&state, 0.0);
    while (fgets(line, (int)sizeof line, stdin) != NULL) {
        double value = strtod(line + (strncmp(line, "reset", 5) == 0 ? 5 : 0), NULL);
        double error_um;
        int code;
        if (strncmp(line, "reset", 5) == 0) {
            gf_ar1_init(&state, value);
            continue;
        }
        code = gf_ar1_step(&state, value, &error_um);
        printf("%d %a\n", code, error_um);
    }
    return 0;
}
"""


SANITIZED = ("-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all")


def c_run(folder: Path, heat, initial: float, *, single: bool, sanitized: bool = False):
    exe = folder / (("sanitized_" if sanitized else "") + ("single" if single else "double"))
    if not exe.exists():
        (folder / "driver.c").write_text(DRIVER)
        flags = [*STRICT_FLAGS, *(SANITIZED if sanitized else ("-O2",)), "-ffp-contract=off"]
        flags += ["-DGF_USE_FLOAT"] if single else []
        sources = [str(folder / "driver.c"), str(folder / "groupfit_ar1.c")]
        subprocess.run(["gcc", *flags, "-I", str(folder), *sources, "-o", str(exe), "-lm"], check=True)
    text = f"reset {float(initial).hex()}\n" + "".join(
        ("nan" if math.isnan(q) else ("inf" if q == math.inf else "-inf" if q == -math.inf else float(q).hex())) + "\n"
        for q in heat
    )
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stdout.split("\n")
    rows = [line.split() for line in out if line]
    return np.array([int(r[0]) for r in rows]), np.array([float.fromhex(r[1]) for r in rows])


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
@pytest.mark.toolchain
@pytest.mark.parametrize("precision", ["double", "single"])
def test_exported_c_equals_replay_bit_for_bit(model, tmp_path, precision):
    write(render(model, "c"), tmp_path)
    heat, observed, _ = simulated_process(n=600, seed=5)
    for run, initial in ((stream(), 0.0), (heat, 0.3), (heat[::-1].copy(), -1.25)):
        fault, prediction = c_run(tmp_path, run, initial, single=precision == "single")
        replay = AR1Rule(model, precision=precision).replay(run, initial_um=initial)
        np.testing.assert_array_equal(fault, replay.fault)
        assert prediction.tobytes() == replay.prediction_um.tobytes()


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
@pytest.mark.toolchain
@pytest.mark.parametrize("precision", ["double", "single"])
def test_sanitized_c_build_takes_hostile_readings_as_replay_does(model, tmp_path, precision):
    """NaN, infinities, -0, subnormals, huge and negative readings: no undefined behaviour, the same outputs."""
    write(render(model, "c"), tmp_path)
    rng = np.random.default_rng(7)
    special = [math.nan, math.inf, -math.inf, -0.0, 5e-324, 1e-310, 1e300, -1e300, 3.4e38, 1e39, -1.0]
    heat = np.array(special * 3 + list(rng.uniform(-100, 5000, 200)) + list(rng.choice(special, 50)))
    fault, prediction = c_run(tmp_path, heat, 0.25, single=precision == "single", sanitized=True)
    replay = AR1Rule(model, precision=precision).replay(heat, initial_um=0.25)
    np.testing.assert_array_equal(fault, replay.fault)
    assert prediction.tobytes() == replay.prediction_um.tobytes()


@pytest.mark.parametrize("name", ["FB__Ar1", "FB_", "Ärger", "END_VAR", "Heat", "c2", "1st"])
def test_a_block_name_that_is_no_structured_text_name_is_refused(model, name):
    with pytest.raises(InputError, match="block name"):
        render(model, "st", name=name)
    assert list(render(model, "st", name="FB_Ar1_Comp")) == ["FB_Ar1_Comp.st"]


def st_block(model: AR1File, real: str):
    """The block evaluated over tree-sitter's tree (tests/support/structured_text.py), which must parse it whole."""
    structured_text = pytest.importorskip("support.structured_text")
    (text,) = render(model, "st", real=real).values()
    assert not structured_text.tree_sitter_errors(text)
    return structured_text.FunctionBlock(text)


@pytest.mark.parametrize("real, precision", [("LREAL", "double"), ("REAL", "single")])
@pytest.mark.toolchain
def test_structured_text_block_equals_replay(model, real, precision):
    block = st_block(model, real)
    cast = np.float32 if real == "REAL" else np.float64
    heat = stream()
    outputs, faults = [], []
    for k, q in enumerate(heat):
        with np.errstate(over="ignore", invalid="ignore"):
            block.call(Heat=cast(q), Reset=(k == 0), InitialUm=cast(0.4))
        outputs.append(float(block.vars["ErrorUm"]))
        faults.append(int(block.vars["Fault"]))
    replay = AR1Rule(model, precision=precision).replay(heat, initial_um=0.4)
    assert np.array(outputs).tobytes() == replay.prediction_um.tobytes()
    np.testing.assert_array_equal(faults, replay.fault)


def test_json_table_runs_the_same_steps(model):
    """A runtime written from the JSON table alone (its numbers and its steps) equals replay."""
    table = json.loads(json.dumps(json_table(model)))
    levels, c2 = table["levels"], table["c2_um"]

    def c2_of(q):
        if q == 0:
            return 0.0
        i = min(range(len(levels)), key=lambda j: (abs(levels[j] - q), j))
        return c2[i] if q == levels[i] else c2[i] * math.pow(q / levels[i], table["heat_exponent"])

    heat, e, out = stream(), 0.9, []
    for k, q in enumerate(heat):
        if k and math.isfinite(q) and 0 <= q <= table["heat_max"]:
            e = table["c1"] * e + c2_of(q)
        out.append(e)
    np.testing.assert_array_equal(out, AR1Rule(model).replay(heat, initial_um=0.9).prediction_um)


def test_controller_sheet_names_the_setting_data(model):
    (sheet,) = render(model, "sheet").values()
    assert "SD43900" in sheet and "MD32750 TEMP_COMP_TYPE = 1" in sheet and "every 15 s" in sheet


def test_bad_ar1_fit_inputs_fail_with_one_line_and_write_nothing(tmp_path, capsys):
    heat, observed, _ = simulated_process(n=300)
    csv = write_run(tmp_path / "run.csv", heat, observed)
    negative = write_run(tmp_path / "negative.csv", np.where(np.arange(300) == 40, -5.0, heat), observed)
    resting = write_run(tmp_path / "resting.csv", np.zeros(300), observed)
    huge = write_run(tmp_path / "huge.csv", np.where(np.arange(300) == 6, 1e300, heat), observed)
    measured = tmp_path / "measured.csv"  # a power that moves every sample: one C2 per reading would be fitted
    power = np.round(heat / 1000 + 0.05 * np.random.default_rng(1).standard_normal(300), 3).clip(0)
    pd.read_csv(csv).assign(power_kW=power).to_csv(measured, index=False)
    out = ["--out", str(tmp_path / "out")]
    cases = (
        (["--data", str(csv)], "--model ar1 needs --heat COLUMN"),
        (["--data", str(csv), "--heat", "nope"], "'nope'"),
        (
            ["--data", str(negative), "--heat", "speed_rpm"],
            "row 41, column 'speed_rpm' = -5: the heat reading must be a finite number from 0 to 1e+09",
        ),
        (["--data", str(csv), "--heat", "speed_rpm", "--p", "2"], "--p is an option of the grouped model"),
        (["--data", str(csv), "--heat", "error_um"], "heat column 'error_um' is the run's error"),
        (["--data", str(measured), "--heat", "power_kW"], "heat column 'power_kW' moves like a measurement"),
        (["--data", str(resting), "--heat", "speed_rpm"], "heat column 'speed_rpm' is 0 on every row"),
        (["--data", str(huge), "--heat", "speed_rpm"], "row 7, column 'speed_rpm' = 1e+300"),
        (["--data", str(csv), "--heat", "speed_rpm", "--period", "3000"], "leaves 2 step(s) of the run's 300 rows"),
        (["--data", str(csv), "--heat", "speed_rpm", "--heat-exponent", "nan"], "--heat-exponent nan: give a number"),
        (["--data", str(csv), "--heat", "speed_rpm", "--heat-exponent", "5"], "--heat-exponent 5: give a number"),
    )
    for options, message in cases:
        assert main(["fit", "--model", "ar1", *options, *out]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out" / "model.json").exists()


def test_a_grouped_model_verb_names_the_ar1_file(model, tmp_path):
    path = tmp_path / "m.json"
    model.save(path)
    from groupfit.model import ModelFile

    with pytest.raises(Exception, match="an AR\\(1\\) model file .*needs a grouped model"):
        ModelFile.load(path)


def test_export_refuses_another_period_and_a_target_it_has_not(model, tmp_path, capsys):
    path = tmp_path / "m.json"
    model.save(path)
    assert main(["export", str(path), "--target", "c", "--period", "10", "--out", str(tmp_path / "a")]) == 2
    assert "an AR(1) model steps every 15 s" in capsys.readouterr().err
    assert main(["export", str(path), "--target", "table", "--out", str(tmp_path / "b")]) == 2
    assert "export target 'table' for an AR(1) model" in capsys.readouterr().err
    assert main(["export", str(path), "--target", "c", "--period", "15", "--out", str(tmp_path / "c")]) == 0


def test_free_run_fit_also_fits_the_structural_gain():
    """E = AR(1) part + g·(T_s − T_s(0)) with g = 3 µm/K; started from g = 2 the free-run fit finds 3."""
    heat, _, spindle = simulated_process(n=900, seed=4)
    rng = np.random.default_rng(4)
    bed = 20 + np.cumsum(rng.normal(0, 0.02, len(heat)))
    observed = spindle + 3.0 * (bed - bed[0]) + rng.normal(0, 0.05, len(heat))
    X = np.column_stack([heat, bed])
    free = AR1Model(structural_gain=2.0, fit_method="free_run", start="zero").fit(X, observed)
    fixed = AR1Model(structural_gain=2.0, start="zero").fit(X, observed)
    assert free.structural_gain_ == pytest.approx(3.0, abs=0.05) and fixed.structural_gain_ == 2.0
    assert free.c1_ == pytest.approx(0.98, abs=2e-3)
    assert np.sqrt(np.mean(free.residuals_**2)) < 0.5 * np.sqrt(np.mean(fixed.residuals_**2))


def test_a_rest_read_as_a_few_tenths_is_rest_not_a_level_of_its_own():
    """A tachometer reading 0…1 r/min at standstill: the fit is that of exact zeros (C2(0) = 0); the free run
    differs by the heat law's C2 of those readings alone (below 0.1 nm here)."""
    heat, observed, _ = simulated_process(noise=0.01, n=900)
    noisy = np.where(heat == 0, np.abs(np.random.default_rng(3).normal(0, 0.5, len(heat))), heat)
    exact = AR1Model().fit(heat[:, None], observed)
    rest = AR1Model().fit(noisy[:, None], observed)
    assert sorted(rest.c2_) == sorted(exact.c2_) == [1000.0, 2000.0]
    assert rest.c1_ == pytest.approx(exact.c1_, rel=1e-12)
    assert rest.predict(noisy[:, None]) == pytest.approx(exact.predict(heat[:, None]), abs=1e-4)


def test_a_level_held_for_a_few_steps_is_read_by_the_heat_law_not_fitted_from_them():
    """A step at 3000 r/min on one row of a run held at 1000 and 2000: its C2 follows the heat law from 2000 (as
    for a level the run never saw), and the noise-free fit recovers C1 and the held levels' C2 exactly."""
    heat, _, _ = simulated_process(n=900)
    heat[500] = 3000.0
    c2 = {0.0: 0.0, 1000.0: 0.05, 2000.0: 0.16, 3000.0: 0.16 * 1.5 ** (5 / 3)}
    error = np.zeros(len(heat))
    for k in range(1, len(heat)):
        error[k] = 0.98 * error[k - 1] + c2[heat[k]]
    estimator = AR1Model().fit(heat[:, None], error)
    assert sorted(estimator.c2_) == [1000.0, 2000.0]
    assert estimator.c1_ == pytest.approx(0.98, rel=1e-12)
    assert estimator.c2_ == pytest.approx({1000.0: 0.05, 2000.0: 0.16}, rel=1e-10)
    assert estimator.c2_for(3000.0) == pytest.approx(c2[3000.0], rel=1e-10)
    assert np.max(np.abs(estimator.residuals_)) < 1e-9
