"""The diagnosis judged as the next run would judge it: held-out conditions, stop rules, honest reports."""

import json

import numpy as np
import pandas as pd
import pytest
from support.diagnose_scenarios import TEMPS, global_model, lumped, sensor_error

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.diagnose import diagnose
from groupfit.diagnose.augment import augment_model
from groupfit.diagnose.candidates import candidate_features, rank_candidates
from groupfit.diagnose.measures import metrics_of
from groupfit.diagnose.policy import DRIFT
from groupfit.diagnose.problem import stacked_residual
from groupfit.diagnose.report import change_words
from groupfit.diagnose.residual import model_inputs
from groupfit.fast_response import without_stage
from groupfit.features import lowpass
from groupfit.heldout.design import stacked_design
from groupfit.heldout.folds import Folds, block_labels, make_folds, operating_columns
from groupfit.heldout.scorer import HeldOutScorer
from groupfit.model import ModelFile

OTHER_SCHEDULE = [[5000.0, 1.0], [3000.0, 0.0], [6000.0, 1.0], [2000.0, 0.0], [30000.0, 1.0]]


def ambient_run(seed, creep_um=0.0, schedule=None, ambient_phase_h=0.0, n_samples=1000):
    """Sensors explain the error except a lag of the ambient; ``creep_um`` adds a probe creep over the run."""
    frame = sensor_error(lumped(seed=seed, n_samples=n_samples, schedule=schedule, ambient_phase_h=ambient_phase_h))
    hours = frame["time_s"].to_numpy() / 3600.0
    frame["error_um"] += 1.2 * lowpass(frame["T_amb"].to_numpy() - 20.0, 3600.0, 100.0) + creep_um * hours / hours[-1]
    return frame


def test_folds_are_whole_conditions_runs_or_blocks():
    frame = pd.DataFrame({"speed": np.repeat([0, 1000, 0, 2000, 0, 3000], 50), "T": np.arange(300.0)})
    folds = make_folds([frame], ["speed", "T"])
    assert folds.kind == "condition" and folds.columns == ("speed",)
    # each fold is one speed level: labels change exactly where the speed does
    assert np.array_equal(np.flatnonzero(np.diff(folds.labels)) + 1, np.flatnonzero(np.diff(frame["speed"])) + 1)
    # a long equilibrium phase is cut so that holding it out leaves enough to train on
    long = pd.DataFrame({"speed": np.r_[np.zeros(20), np.full(580, 2000.0)], "T": np.arange(600.0)})
    pieces = np.bincount(make_folds([long], ["speed"]).labels)
    assert pieces.max() <= np.ceil(600 / 6) and pieces.min() >= 20
    # several runs: leave one run out; no operating column: blocks of time
    runs = [frame.iloc[:100], frame.iloc[100:220], frame.iloc[220:]]
    assert make_folds(runs, ["speed"]).kind == "run" and make_folds(runs, ["speed"]).n_folds == 3
    assert make_folds([frame[["T"]]], ["T"]).kind == "block"
    for train, test in folds.splits():
        assert not (train & test).any() and (train | test).all()


def test_settings_move_in_steps_and_measurements_do_not():
    rng = np.random.default_rng(3)
    n = 2880  # a day at 30 s
    spectrum = np.repeat(rng.choice(np.arange(500, 6001, 125), size=72), 40)  # 72 speeds of 20 min, 45 levels
    ambient = np.round(20.0 + 2.0 * np.sin(np.linspace(0.0, 2 * np.pi, n)), 1)  # read to 0.1 K, no noise
    frame = pd.DataFrame(
        {"speed": spectrum, "reverse": spectrum * np.where(np.arange(n) % 960 < 480, 1, -1), "T_amb": ambient}
    )
    assert operating_columns(frame, ["speed", "reverse", "T_amb"]) == ["speed", "reverse"]
    folds = make_folds([frame], ["speed", "T_amb"])
    assert folds.kind == "condition" and folds.columns == ("speed",) and folds.n_folds >= 20
    # the heat law takes the magnitude of a speed logged with its direction (M3 positive, M4 negative)
    features = candidate_features(["reverse"], [], frame, operating=["reverse"])
    heat = next(f for f in features if f.transform == "lowpass" and f.exponent)
    assert heat.exponent == pytest.approx(5 / 3) and heat.scale == 1000.0 and heat.start == "rest"
    magnitude = lowpass((spectrum / 1000.0) ** (5 / 3), heat.tau_s, 30.0, before=0.0)
    np.testing.assert_allclose(heat.compute(frame["reverse"].to_numpy(float), 30.0), magnitude, rtol=1e-12)


def test_a_tempting_but_harmful_second_effect_is_not_added():
    """A probe creep on the modelling run only: blocked-in-time CV adds a long low-pass of a sensor for it."""
    modelling = ambient_run(0, creep_um=0.6)
    validation = ambient_run(1, schedule=OTHER_SCHEDULE, ambient_phase_h=7.0)
    run, val = load_run(modelling, temps=TEMPS), load_run(validation, temps=TEMPS)
    model = global_model(run)

    result = diagnose(model, run, val, own_transforms=True)
    assert [c.feature.column for c in result.added] == ["T_amb"]
    assert result.after["validate"]["rms_um"] <= 0.6 * result.before["validate"]["rms_um"]
    assert result.improved is True

    # the previous acceptance (10 blocks in time, every transform, 30 %) adds two effects, the second harmful
    def best_by_blocks(current):
        ranked = rank_candidates(
            run.error,
            candidate_features(["T_amb", "spindle_on"], TEMPS, modelling),
            lambda f: f.compute(modelling[f.column].to_numpy(float), 100.0),
            HeldOutScorer(
                run.error,
                stacked_design(current, [model_inputs(current, run)]),
                Folds(block_labels(run.n_samples, 10), "block"),
            ),
        )
        return ranked[0]

    first_effect = best_by_blocks(model)
    assert first_effect.feature.column == "T_amb"
    first = augment_model(model, run, model_inputs(model, run), first_effect.feature).to_dict()
    tempting = best_by_blocks(first)
    assert tempting.score >= 0.3 and tempting.feature.column in TEMPS
    second = augment_model(first, run, model_inputs(first, run), tempting.feature).to_dict()
    rms = lambda m, r: metrics_of(stacked_residual(m, [r], None))["rms_um"]  # noqa: E731
    assert rms(second, run) < rms(first, run)
    assert rms(second, val) > rms(first, val)


def test_a_worse_validation_is_said_first_and_in_json(tmp_path, capsys):
    """The modelling run has an ambient effect the validation run does not share: the added effect hurts there."""
    modelling = ambient_run(0)
    validation = sensor_error(lumped(seed=1, n_samples=1000, schedule=OTHER_SCHEDULE, ambient_phase_h=7.0))
    paths = {}
    for name, frame in (("modelling", modelling), ("validation", validation)):
        paths[name] = tmp_path / f"{name}.csv"
        frame.to_csv(paths[name], index=False)
    model_dir = tmp_path / "model"
    args = ["fit", "--data", str(paths["modelling"]), "--temps", ",".join(TEMPS), "--p", "0", "--quiet"]
    args += ["--reference", "none"]  # the lumped machine's error is defined on absolute readings
    assert main([*args, "--out", str(model_dir)]) == 0
    capsys.readouterr()
    code = main(
        [
            "diagnose",
            str(model_dir / "model.json"),
            "--data",
            str(paths["modelling"]),
            "--validate",
            str(paths["validation"]),
            "--out",
            str(tmp_path / "d"),
            "--json",
            str(tmp_path / "d.json"),
        ]
    )
    assert code == 0
    report = capsys.readouterr().out.splitlines()
    result = json.loads((tmp_path / "d.json").read_text())
    before, after = result["before"]["validate"]["rms_um"], result["after"]["validate"]["rms_um"]
    assert result["added"][0]["column"] == "T_amb" and after > before
    assert result["improved"] is False
    assert report[0].startswith("the augmented model is worse on validation") and "not recommended" in report[0]
    assert "% higher)" in "\n".join(report)


def test_worse_on_one_of_several_validation_runs_is_not_reported_as_better():
    """Better on the validation runs together, worse on one of them: the report names that run, first."""
    modelling = ambient_run(0)
    with_effect = ambient_run(2, schedule=OTHER_SCHEDULE, ambient_phase_h=7.0)
    without = sensor_error(lumped(seed=1, n_samples=1000, schedule=OTHER_SCHEDULE, ambient_phase_h=7.0))
    run = load_run(modelling, temps=TEMPS)
    validation = [
        load_run(with_effect, temps=TEMPS, name="with_effect"),
        load_run(without, temps=TEMPS, name="without"),
    ]
    model = global_model(run)

    result = diagnose(model, run, validation)
    assert [c.feature.column for c in result.added] == ["T_amb"]
    # each run's RMS, replayed on its own, against the stacked residuals cut per run
    rms = lambda m, r: metrics_of(stacked_residual(m, [r], None))["rms_um"]  # noqa: E731
    for entry, val in zip(result.validation_runs, validation):
        assert entry.name == val.name
        assert entry.before["rms_um"] == pytest.approx(rms(model, val), rel=1e-12)
        assert entry.after["rms_um"] == pytest.approx(rms(result.model, val), rel=1e-12)
    together_before, together_after = result.before["validate"]["rms_um"], result.after["validate"]["rms_um"]
    assert together_after < together_before  # the pooled RMS alone would call it better
    assert rms(result.model, validation[1]) > rms(model, validation[1])
    assert result.improved is False and [r.name for r in result.worse_runs] == ["without"]
    head = result.summary().splitlines()[0]
    assert head.startswith("the augmented model is worse on without:") and head.endswith("not recommended")
    assert "(the 2 validation runs together:" in head
    as_json = json.loads(json.dumps(result.to_json()))
    assert as_json["improved"] is False and [r["name"] for r in as_json["validation_runs"]] == [
        "with_effect",
        "without",
    ]


def test_percentages_read_right():
    assert change_words(11.0, 4.4) == "11 → 4.4 µm (60 % lower)"
    assert change_words(11.0, 19.8) == "11 → 19.8 µm (80 % higher)"
    assert change_words(2.0, 2.0) == "2 → 2 µm (unchanged)"


def test_several_runs_are_held_out_one_at_a_time(tmp_path, capsys):
    frames = [ambient_run(seed, n_samples=400, ambient_phase_h=3.0 * seed) for seed in range(3)]
    paths = []
    for k, frame in enumerate(frames):
        paths.append(tmp_path / f"day{k}.csv")
        frame.to_csv(paths[-1], index=False)
    model_dir = tmp_path / "model"
    assert (
        main(
            [
                "fit",
                "--data",
                *map(str, paths),
                "--temps",
                ",".join(TEMPS),
                "--p",
                "0",
                "--quiet",
                "--reference",
                "none",
                "--out",
                str(model_dir),
            ]
        )
        == 0
    )
    # the global model on several runs is the least-squares fit on all their samples
    model = without_stage(ModelFile.load(model_dir / "model.json")).to_dict()  # without the probe checks' stage
    X = np.vstack([f[TEMPS].to_numpy() for f in frames])
    y = np.concatenate([f["error_um"].to_numpy() for f in frames])
    reference = np.linalg.lstsq(np.column_stack([np.ones(len(y)), X]), y, rcond=None)[0]
    np.testing.assert_allclose(model["coefficients"][0], reference, rtol=1e-7, atol=1e-9)
    # a grouped model's breaks belong to one run
    capsys.readouterr()
    fit = ["fit", "--data", *map(str, paths), "--temps", ",".join(TEMPS), "--p", "2", "--quiet"]
    assert main([*fit, "--out", str(tmp_path / "m")]) == 2
    assert "several runs fit a global model" in capsys.readouterr().err

    runs = [load_run(p, temps=TEMPS) for p in paths]
    result = diagnose(model, runs)
    assert result.folds.startswith("leave-one-run-out over 3 runs")
    assert result.added[0].feature.column == "T_amb" and len(result.added[0].fold_ratios) == 3


def test_runs_read_from_excel_and_parquet_like_csv(tmp_path):
    frame = ambient_run(0, n_samples=120).rename(columns={"time_s": "时间"})
    frame.to_csv(tmp_path / "run.csv", index=False)
    frame.to_excel(tmp_path / "run.xlsx", index=False)
    frame.to_parquet(tmp_path / "run.parquet", index=False)
    reference = load_run(tmp_path / "run.csv", temps=TEMPS, time="时间")
    for suffix in ("xlsx", "parquet"):
        run = load_run(tmp_path / f"run.{suffix}", temps=TEMPS, time="时间")
        np.testing.assert_allclose(run.temps, reference.temps, rtol=1e-12)
        np.testing.assert_allclose(run.error, reference.error, rtol=1e-12)
        assert run.period == pytest.approx(100.0)


def test_a_broken_workbook_is_one_line(tmp_path, capsys):
    bad = tmp_path / "broken.xlsx"
    bad.write_bytes(b"not a workbook")
    assert main(["fit", "--data", str(bad), "--temps", "T1", "--p", "0", "--out", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "broken.xlsx: not a readable Excel table (its bytes begin as no workbook" in err[0]
    assert not (tmp_path / "m").exists()


def test_fit_select_keeps_the_sensors_that_carry_the_error(tmp_path, capsys):
    rng = np.random.default_rng(5)
    frame = lumped(seed=4, n_samples=600)
    for k in range(5, 9):  # four sensors that only see noise and a drift of their own
        frame[f"T{k}"] = 20.0 + np.cumsum(rng.normal(scale=0.02, size=len(frame)))
    frame["error_um"] = 0.9 * frame["T1"] + 1.7 * frame["T3"] + rng.normal(scale=0.02, size=len(frame))
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    temps = ",".join(f"T{k}" for k in (1, 3, 5, 6, 7, 8))
    out = tmp_path / "model"
    capsys.readouterr()
    args = ["fit", "--data", str(path), "--temps", temps, "--p", "0", "--select", "forward", "--json", "-"]
    args += ["--reference", "none"]  # the error is defined on absolute readings
    assert main([*args, "--quiet", "--out", str(out)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert sorted(result["input_selection"]["inputs"]) == ["T1", "T3"]
    assert result["temps"] == result["input_selection"]["inputs"]


def test_diagnose_can_start_from_re_selected_inputs(tmp_path, capsys):
    rng = np.random.default_rng(6)
    frame = ambient_run(2, n_samples=600)
    for k in range(5, 9):  # sensors that see only noise: a base model that over-fits on them
        frame[f"T{k}"] = 20.0 + rng.normal(scale=0.05, size=len(frame))
    path = tmp_path / "run.csv"
    frame.to_csv(path, index=False)
    temps = ",".join(f"T{k}" for k in range(1, 9))
    model_dir = tmp_path / "model"
    args = ["fit", "--data", str(path), "--temps", temps, "--p", "0", "--quiet", "--reference", "none"]
    assert main([*args, "--out", str(model_dir)]) == 0
    capsys.readouterr()
    args = ["diagnose", str(model_dir / "model.json"), "--data", str(path), "--select", "forward"]
    assert main([*args, "--out", str(tmp_path / "d"), "--json", str(tmp_path / "d.json")]) == 0
    report = capsys.readouterr().out.splitlines()
    result = json.loads((tmp_path / "d.json").read_text())
    chosen = result["selection"]["inputs"]
    assert report[0].startswith("inputs re-selected by forward") and set(chosen) <= set(TEMPS)
    augmented = json.loads((tmp_path / "d" / "model_augmented.json").read_text())
    assert augmented["temps"][: len(chosen)] == chosen
    assert result["added"][0]["column"] == "T_amb"
    # before is the model as given (eight inputs), whatever was re-selected
    assert result["before"]["data"]["rms_um"] == pytest.approx(
        json.loads((model_dir / "model.json").read_text())["training"]["rms_um"]
    )


def test_an_effect_that_doubles_the_error_of_one_held_out_condition_is_refused():
    from groupfit.diagnose.candidates import Candidate
    from groupfit.diagnose.policy import DEFAULT_POLICY, FOLD_WORSENED
    from groupfit.features import Feature

    def candidate(worst_ratio):
        ratios = (0.2, 0.3, 0.25, 0.4, worst_ratio)  # four conditions much better, one worse
        return Candidate(Feature("speed", "lowpass", tau_s=3600.0), 0.7, 1.0, 2.0, ratios, ratios)

    limit = DEFAULT_POLICY.max_fold_worsening**2  # the folds hold squared errors
    for stage in ("first", "joint", "reference"):  # a further effect must better every fold
        assert DEFAULT_POLICY.refusal(candidate(0.999 * limit), stage) is None
        refusal = DEFAULT_POLICY.refusal(candidate(1.001 * limit), stage)
        assert refusal.rule_id == FOLD_WORSENED
        assert refusal.reason == f"makes one held-out condition (fold 5) {np.sqrt(1.001 * limit):.1f} times worse (RMS)"


@pytest.mark.parametrize(
    "column, words",
    [
        ("T_amb", "ambient temperature `T_amb`"),
        ("T_room", "ambient temperature `T_room`"),
        ("air_C", "ambient temperature `air_C`"),
        ("src_zscrew_on", "heat source 'zscrew' (on/off `src_zscrew_on`)"),
        ("pump_on", "heat source 'pump' (on/off `pump_on`)"),
        ("Speed_RPM", "spindle speed, a part that lags it (`Speed_RPM`)"),
        ("T9", "column `T9`"),
    ],
)
def test_the_report_names_the_effect_in_words(column, words):
    from groupfit.diagnose.report import column_words

    assert column_words(column) == words


def test_an_effect_no_better_than_a_drift_of_the_run_is_not_added():
    """Nothing physical is missing; the probe creeps over the modelling run. A long low-pass would follow the creep."""
    frame = sensor_error(lumped(seed=5, n_samples=1000))
    hours = frame["time_s"].to_numpy() / 3600.0
    frame["error_um"] += 0.15 * hours  # µm/h
    run = load_run(frame, temps=TEMPS)
    result = diagnose(global_model(run), run)
    assert not result.added
    assert DRIFT in {refused.rule_id for refused in result.refused}
    # without the creep the same run has nothing to refuse on that ground
    clean = load_run(sensor_error(lumped(seed=5, n_samples=1000)), temps=TEMPS)
    clean_result = diagnose(global_model(clean), clean)
    assert DRIFT not in {refused.rule_id for refused in clean_result.refused}


def test_an_unused_sensor_that_follows_no_heat_source_is_read_as_the_ambient():
    from groupfit.diagnose.problem import exogenous_sensors

    frame = lumped(seed=6, n_samples=600)  # T_amb: a daily sine and an HVAC step, not the machine's heat
    frame["T9"] = frame.pop("T_amb")
    frame["T5"] = 20.0 + 3.0 * lowpass(frame["spindle_on"].to_numpy(float), 5400.0, 100.0, before=0.0)
    run = load_run(frame, temps=TEMPS)
    assert exogenous_sensors([run], ["T5", "T9"], ["spindle_on"], 100.0) == ["T9"]
