"""Models run at the controller's sampling period: check-run models on a fast stream, lags rescaled exactly.

The truths: the model evaluated directly (``ModelFile.predict_position``) on
every sample, and the closed-form response of a continuous first-order lag
to a step, ``v1 + (v0 − v1)·e^{−(t − ts)/τ}``; a delay rescaled reads the
source ``D·Δt`` seconds back.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from support.json_runtime import run_table
from test_position import fitted
from test_switching_models import augmented_model

from groupfit.cli import main
from groupfit.diagnose.augment import augment_model
from groupfit.diagnose.residual import model_inputs
from groupfit.errors import InputError
from groupfit.export import render
from groupfit.features import Feature
from groupfit.model import ModelFile
from groupfit.runtime import RuleTables, SwitchingRule
from groupfit.runtime.period import at_period


def fast_stream(model: dict, period: float, n: int, seed: int = 0) -> pd.DataFrame:
    """Readings every ``period`` s: the check runs' temperatures interpolated, the axis anywhere on its travel."""
    rng = np.random.default_rng(seed)
    tables = RuleTables.from_model(model)
    t = np.arange(n) * period
    frame = pd.DataFrame({"time_s": t})
    for k, name in enumerate(tables.raw_names):
        if k == tables.position_reading:
            frame[name] = rng.uniform(tables.travel_min_mm, tables.travel_max_mm, n)
        else:
            frame[name] = 20.0 + 2.0 * k + 3.0 * (1 - np.exp(-t / 1500.0)) + 0.01 * rng.standard_normal(n)
    return frame


def test_a_p0_position_model_fitted_on_20_min_checks_replays_a_10_s_stream(tmp_path, capsys):
    model, _ = fitted(order=2, p=0)
    assert model.sampling_period_s == 1200.0 and not model.breaks
    (tmp_path / "model.json").write_text(json.dumps(model.to_dict()))
    frame = fast_stream(model.to_dict(), 10.0, 240)
    frame.to_csv(tmp_path / "live.csv", index=False)
    code = main(["replay", str(tmp_path / "model.json"), "--data", str(tmp_path / "live.csv"), "--json", "-"])
    assert code == 0
    result = json.loads(capsys.readouterr().out)
    assert result["sampling_period_s"] == 10.0 and result["model_period_s"] == 1200.0 and result["rescaled"]
    direct = model.predict_position(
        frame[["T1", "T2"]].to_numpy(), frame["P_mm"].to_numpy(), np.zeros(len(frame), dtype=int)
    )
    replayed = np.array([s["prediction_um"] for s in result["samples"]])
    assert np.max(np.abs(replayed - direct)) < 1e-9
    assert all(s["fault"] == 0 for s in result["samples"])


def test_a_model_with_breaks_is_refused_at_another_period_with_one_line(tmp_path, capsys):
    model, _ = fitted(order=1, p=1)
    (tmp_path / "model.json").write_text(json.dumps(model.to_dict()))
    fast_stream(model.to_dict(), 10.0, 50).to_csv(tmp_path / "live.csv", index=False)
    args = ["replay", str(tmp_path / "model.json"), "--data", str(tmp_path / "live.csv"), "--json"]
    assert main([*args, str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "sampling period 10 s differs from the model's 1200 s" in err[0]
    assert f"breaks at samples {model.breaks[0]}" in err[0]
    assert not (tmp_path / "r.json").exists()
    assert main(["export", str(tmp_path / "model.json"), "--target", "c", "--period", "10", "--out", "x"]) == 2
    assert "breaks at samples" in capsys.readouterr().err and not (tmp_path / "x").exists()


def step_readings(tables: RuleTables, t: np.ndarray, ts: float, levels: tuple[float, float]) -> np.ndarray:
    """Measured inputs at mid-range; the source steps from ``levels[0]`` to ``levels[1]`` at ``ts``.

    Sample k carries the value the source held over ``(t_{k−1}, t_k]``, so it
    reads the new level from the first sample after ``ts``.
    """
    readings = np.empty((len(t), tables.n_temps))
    for r in range(tables.n_temps):
        readings[:, r] = 0.5 * (tables.valid_min[r] + tables.valid_max[r])
    source = tables.derived[0].reading
    readings[:, source] = np.where(t - ts > 1e-9, levels[1], levels[0])
    return readings


@pytest.mark.parametrize("period", [100.0, 10.0, 7.0])
def test_a_low_pass_rescaled_is_the_same_continuous_filter(period):
    """At its own 100 s and rescaled to 10 s and 7 s, the lag of a step is v1 + (v0 − v1)·e^{−(t − ts)/τ}."""
    model, _ = augmented_model("lowpass p=0")
    tau, ts = 1800.0, 700.0  # the step on a sample of every period
    t = np.arange(0.0, 9000.0, period)
    rule = SwitchingRule(model, period_s=period)
    rule.reset()
    lagged = []
    for row in step_readings(rule.tables, t, ts, (20.0, 23.0)):
        rule.step(row)
        lagged.append(rule.input_values()[-1])
    exact = np.where(t > ts, 23.0 - 3.0 * np.exp(-(t - ts) / tau), 20.0)
    assert np.max(np.abs(np.array(lagged) - exact)) < 1e-9


def test_the_json_export_at_another_period_runs_the_rescaled_rule():
    model, _ = augmented_model("lowpass p=0")
    table = json.loads(render(at_period(model, 10.0), "json")["groupfit_runtime.json"])
    rule = SwitchingRule(model, period_s=10.0)
    t = np.arange(0.0, 3000.0, 10.0)
    readings = step_readings(rule.tables, t, 700.0, (20.0, 23.0))
    replay = rule.replay(readings)
    rebuilt = run_table(table, readings)
    assert [r[2] for r in rebuilt] == replay.prediction_um.tolist()
    assert [r[3] for r in rebuilt] == replay.compensation_um.tolist()
    assert table["sampling_period_s"] == 10.0


def test_hold_and_rate_limit_keep_their_meaning_in_seconds():
    model, _ = augmented_model("lowpass p=0")
    loaded = ModelFile.coerce(model)
    slow, fast = at_period(model, 300.0), at_period(model, 10.0)
    hold_s = loaded.switching.hold_samples * 100.0
    assert slow.switching.hold_samples == max(1, math.floor(hold_s / 300.0))
    assert fast.switching.hold_samples == math.floor(hold_s / 10.0)
    assert slow.switching.rate_limit_um == pytest.approx(3 * loaded.switching.rate_limit_um)
    assert fast.switching.rate_limit_um == loaded.switching.rate_limit_um


def test_a_delay_rescales_to_whole_samples_and_is_refused_otherwise():
    model, run = augmented_model("lowpass p=0")
    delayed = augment_model(model, run, model_inputs(model, run), Feature("T_amb", "delay", delay_samples=3)).to_dict()
    fast = at_period(delayed, 25.0)
    assert fast.temps[-1] == "T_amb~delay12" and fast.derived_inputs[-1].delay_samples == 12
    t = np.arange(0.0, 2000.0, 25.0)
    rule = SwitchingRule(delayed, period_s=25.0)
    readings = step_readings(rule.tables, t, 0.0, (20.0, 20.0))
    source = rule.tables.derived[-1].reading
    readings[:, source] = 20.0 + 0.001 * t  # a ramp: the delayed value names the time it was read
    rule.reset()
    seen = []
    for row in readings:
        rule.step(row)
        seen.append(rule.input_values()[-1])
    later = t >= 300.0
    assert np.allclose(np.array(seen)[later], 20.0 + 0.001 * (t[later] - 300.0), rtol=0, atol=1e-12)
    with pytest.raises(InputError, match=r"delays its source by 3 sample\(s\) \(300 s\), which is no whole number"):
        at_period(delayed, 200.0)


@pytest.mark.parametrize("period", [1e-9, 0.0, -10.0, 1e300, math.nan])
def test_a_period_no_controller_samples_at_is_refused_naming_the_range(period):
    model, _ = augmented_model("lowpass p=0")
    with pytest.raises(InputError, match=r"a sampling period must be a number of seconds from 0\.0001 to 1e\+11"):
        at_period(model, period)
