"""The default reference questioned by the next-run estimate: the air's temperature, or none.

Runs of a machine whose parts warm over the air by a speed programme, in a
room whose air swings over the day. The error follows either the parts'
rises over the air (a structure that expands with the room) or their
temperatures over 20 °C (an error measured against a length that stays at
20 °C). A next day is another air level; the truth is known by construction,
so which reference holds on it is known too.
"""

import json

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import load_run
from groupfit.heldout.reference_choice import SIGNAL_TO_NOISE, ambient_signal_to_noise, choose_reference
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor
from groupfit.reference import with_reference

GAINS = (3.0, -1.5, 2.0)
SPEEDS = (0, 2000, 4000, 1000, 3000, 0, 4000, 2000)
HOURS_PER_SPEED = 2.0
PERIOD_S = 60.0


def machine_day(seed: int, *, air_level: float, air_swing: float, truth: str) -> pd.DataFrame:
    """One day: three parts lag the speed programme over the air; the error from the parts by ``truth``."""
    rng = np.random.default_rng(seed)
    per_speed = int(HOURS_PER_SPEED * 3600 / PERIOD_S)
    speed = np.repeat(np.roll(SPEEDS, seed), per_speed).astype(float)
    n = len(speed)
    hours = np.arange(n) * PERIOD_S / 3600
    air = air_level + air_swing * np.sin(2 * np.pi * (hours - 6.0) / 24.0) + 0.03 * rng.standard_normal(n)
    parts = []
    for k, tau_h in enumerate((0.5, 1.5, 3.0)):
        rise = np.zeros(n)
        heat = (1.0 + 0.5 * k) * speed / 1000.0
        for i in range(1, n):
            rise[i] = rise[i - 1] + (heat[i] - rise[i - 1]) * PERIOD_S / (tau_h * 3600)
        lagged_air = np.copy(air)  # a part follows the air with its own lag too
        for i in range(1, n):
            lagged_air[i] = lagged_air[i - 1] + (air[i] - lagged_air[i - 1]) * PERIOD_S / (tau_h * 3600)
        parts.append(lagged_air + rise)
    parts = np.array(parts).T
    over = parts - (air[:, None] if truth == "rises" else 20.0)
    error = over @ np.array(GAINS) + 0.05 * rng.standard_normal(n)
    frame = pd.DataFrame(parts + 0.02 * rng.standard_normal(parts.shape), columns=["T1", "T2", "T3"])
    frame.insert(0, "time_s", PERIOD_S * np.arange(n))
    return frame.assign(T_amb=air, spindle_rpm=speed, error_um=error)


def run_of(frame: pd.DataFrame, name: str = "day"):
    return load_run(frame, temps=["T1", "T2", "T3"], name=name)


# ------------------------------------------------------------------------- the ambient moves, or not


def test_the_ambient_s_signal_to_noise_is_its_spread_over_its_white_scatter():
    rng = np.random.default_rng(0)
    sigma = 0.05
    white = 20.0 + sigma * rng.standard_normal(20000)
    spread, ratio = ambient_signal_to_noise([white])
    assert spread == pytest.approx(sigma, rel=0.03) and ratio == pytest.approx(1.0, rel=0.03)
    amplitude = 2.0  # a slow swing: its spread is A/√2 (closed form), its steps almost nothing
    swing = 20.0 + amplitude * np.sin(np.linspace(0.0, 4 * np.pi, 20000)) + sigma * rng.standard_normal(20000)
    spread, ratio = ambient_signal_to_noise([swing])
    assert spread == pytest.approx(np.hypot(amplitude / np.sqrt(2), sigma), rel=0.03)
    assert ratio == pytest.approx(spread / sigma, rel=0.05) and ratio > 5 * SIGNAL_TO_NOISE
    # two steady days at two levels: each run's scatter is white, the level between them moves
    spread, ratio = ambient_signal_to_noise([white[:10000], white[10000:] + 3.0])
    assert spread == pytest.approx(np.hypot(1.5, sigma), rel=0.03) and ratio > SIGNAL_TO_NOISE


def test_two_steady_days_at_two_air_levels_are_an_ambient_that_moves(tmp_path):
    days = [machine_day(k, air_level=level, air_swing=0.0, truth="absolute") for k, level in ((4, 20.0), (5, 23.0))]
    for day in days:
        day["T_amb"] = day["T_amb"].round(0)  # a steady reading with no scatter at all: the ratio is unbounded
    choice = choose_reference([run_of(day) for day in days], "T_amb", (0,))
    assert choice.signal_to_noise == np.inf and choice.scored and choice.reference is None
    record = choice.to_json()
    assert record["ambient_signal_to_noise"] is None  # JSON has no infinity
    json.dumps(record, allow_nan=False)


def test_an_ambient_that_stays_within_its_noise_leaves_the_default_unquestioned():
    frame = machine_day(1, air_level=20.0, air_swing=0.0, truth="absolute")
    choice = choose_reference([run_of(frame)], "T_amb", (0, 1))
    assert choice.reference == "T_amb" and not choice.scored
    assert "stays within its noise" in choice.reason() and choice.to_json()["candidates"] == []


# ------------------------------------------------------------------------- the choice, and the next day


def next_day_rms(run, next_frame: pd.DataFrame, reference) -> float:
    """A global model on ``run`` with ``reference`` replayed over the next day (truth by construction)."""
    fitted = with_reference(run, reference)
    model = ModelFile.coerce(GroupedRegressor(p=0).fit(fitted.temps, fitted.error).to_model_file(fitted))
    prediction = model.predict(model.inputs(next_frame))  # the model's reference applied to the readings
    return float(np.sqrt(np.mean((next_frame["error_um"].to_numpy() - prediction) ** 2)))


@pytest.mark.parametrize("truth, expected", [("absolute", None), ("rises", "T_amb")])
def test_the_reference_chosen_is_the_one_that_holds_on_a_day_at_another_air_level(truth, expected):
    day = machine_day(2, air_level=21.0, air_swing=2.0, truth=truth)
    next_day = machine_day(3, air_level=24.0, air_swing=2.0, truth=truth)
    run = run_of(day)
    choice = choose_reference([run], "T_amb", (0, 1, 2))
    assert choice.scored and choice.reference == expected
    held = {reference: next_day_rms(run, next_day, reference) for reference in ("T_amb", None)}
    other = None if expected == "T_amb" else "T_amb"
    assert held[expected] < 0.5 * held[other]  # the truth: the choice holds on the next day, the other does not
    record = choice.to_json()
    assert record["chosen"] == expected and record["default"] == "T_amb"
    assert {c["reference"] for c in record["candidates"]} == {"T_amb", None}


def quiet_air_day(seed: int, *, air_level: float, truth: str) -> pd.DataFrame:
    """A day whose air moves (0.15 °C of swing, above its noise) too little against the error's noise (2 µm) for
    the folds to tell the references apart."""
    frame = machine_day(seed, air_level=air_level, air_swing=0.15, truth=truth)
    return frame.assign(error_um=frame["error_um"] + 2.0 * np.random.default_rng(7).standard_normal(len(frame)))


@pytest.mark.parametrize("truth", ["absolute", "rises"])
def test_a_run_that_cannot_tell_the_references_apart_says_what_a_day_at_another_air_level_costs(truth):
    day = quiet_air_day(2, air_level=21.0, truth=truth)
    next_day = machine_day(3, air_level=24.0, air_swing=0.15, truth=truth)
    run = run_of(day)
    choice = choose_reference([run], "T_amb", (0, 1, 2))
    assert choice.scored and not choice.told_apart and choice.reference == "T_amb"  # the default stands
    if truth == "absolute":  # the slope of the absolute readings' model: the sum of the error's gains
        assert choice.air_slope_um_per_c == pytest.approx(sum(GAINS), rel=0.05)
    # the next day, 3 °C warmer: the two references part by about the slope times the change, whichever holds
    shift = next_day["T_amb"].mean() - day["T_amb"].mean()
    held = {reference: next_day_rms(run, next_day, reference) for reference in ("T_amb", None)}
    assert abs(held["T_amb"] - held[None]) == pytest.approx(choice.air_slope_um_per_c * shift, rel=0.1)
    assert held["T_amb" if truth == "rises" else None] < 1.0  # the truth's reference holds (noise 2 µm not in it)
    note = choice.note()
    assert "cannot tell" in note and f"{choice.air_slope_um_per_c:.3g} µm for every °C" in note
    record = choice.to_json()
    assert record["told_apart"] is False and record["note"] == note
    assert record["air_slope_um_per_c"] == pytest.approx(choice.air_slope_um_per_c)


def test_a_run_that_tells_the_references_apart_has_no_such_note():
    choice = choose_reference([run_of(machine_day(2, air_level=21.0, air_swing=2.0, truth="rises"))], "T_amb", (0,))
    assert choice.scored and choice.told_apart and choice.note() is None
    assert choice.to_json()["told_apart"] is True and choice.to_json()["note"] is None
    steady = choose_reference([run_of(machine_day(1, air_level=20.0, air_swing=0.0, truth="rises"))], "T_amb", (0,))
    assert not steady.scored and steady.note() is None and steady.to_json()["told_apart"] is None


# ------------------------------------------------------------------------- the verbs


def write_days(tmp_path, truth: str):
    paths = []
    for k, level in enumerate((21.0, 24.0)):
        path = tmp_path / f"day{k}_{truth}.csv"
        machine_day(2 + k, air_level=level, air_swing=2.0, truth=truth).to_csv(path, index=False)
        paths.append(path)
    return paths


def fit_cli(tmp_path, data, *options) -> tuple[dict, str]:
    out = tmp_path / "fit"
    args = ["fit", "--data", *map(str, data), "--temps", "T1,T2,T3", "--recalibrate", "none", "--quiet"]
    assert main([*args, *options, "--out", str(out), "--force", "--json", str(tmp_path / "fit.json")]) == 0
    return json.loads((out / "model.json").read_text()), (tmp_path / "fit.json").read_text()


def test_fit_drops_the_default_reference_when_the_error_follows_the_parts_own_temperatures(tmp_path, capsys):
    day, next_day = write_days(tmp_path, "absolute")
    model, _ = fit_cli(tmp_path, [day])
    assert model.get("reference") is None
    choice = model["training"]["reference_choice"]
    assert choice["chosen"] is None and choice["default"] == "T_amb" and choice["ambient_signal_to_noise"] > 3
    none, over_air = (next(c for c in choice["candidates"] if c["reference"] == r) for r in (None, "T_amb"))
    assert none["expected_next_run_rms_um"] < over_air["expected_next_run_rms_um"]
    report = capsys.readouterr()
    assert "reference none (absolute readings), chosen by the next-run estimate" in report.out + report.err
    # the model file replays the next day on absolute readings, as it was chosen
    replayed = tmp_path / "replay.json"
    assert main(["replay", str(tmp_path / "fit" / "model.json"), "--data", str(next_day), "--json", str(replayed)]) == 0
    chosen_rms = json.loads(replayed.read_text())["rms_um"]
    assert chosen_rms < 0.5 * next_day_rms(run_of(pd.read_csv(day)), pd.read_csv(next_day), "T_amb")


def test_a_reference_the_user_names_is_never_questioned(tmp_path):
    day, _ = write_days(tmp_path, "absolute")
    model, _ = fit_cli(tmp_path, [day], "--reference", "T_amb")
    assert model["reference"] == "T_amb" and "reference_choice" not in model["training"]


def test_fit_keeps_the_air_when_the_error_follows_the_rises_over_it(tmp_path):
    day, _ = write_days(tmp_path, "rises")
    model, _ = fit_cli(tmp_path, [day])
    assert model["reference"] == "T_amb" and model["training"]["reference_choice"]["chosen"] == "T_amb"


def test_several_runs_decide_by_leaving_one_run_out(tmp_path):
    days = write_days(tmp_path, "absolute")
    model, _ = fit_cli(tmp_path, days, "--p", "0")
    choice = model["training"]["reference_choice"]
    assert model.get("reference") is None and choice["chosen"] is None
    assert model["training"]["expected_next_run_method"].startswith("leave-one-run-out")


def test_compare_takes_the_reference_fit_would_take(tmp_path):
    day, next_day = write_days(tmp_path, "absolute")
    out = tmp_path / "cmp"
    args = ["compare", "--data", str(day), "--validate", str(next_day), "--temps", "T1,T2,T3", "--pmax", "2"]
    args += ["--heat", "none"]
    assert main([*args, "--out", str(out), "--json", str(tmp_path / "cmp.json"), "--quiet"]) == 0
    result = json.loads((tmp_path / "cmp.json").read_text())
    assert result["reference_choice"]["chosen"] is None and result.get("reference") is None


def test_fit_says_when_its_run_cannot_tell_the_references_apart(tmp_path, capsys):
    day = tmp_path / "quiet_air.csv"
    quiet_air_day(2, air_level=21.0, truth="absolute").to_csv(day, index=False)
    model, _ = fit_cli(tmp_path, [day])
    choice = model["training"]["reference_choice"]
    assert model["reference"] == "T_amb" and choice["told_apart"] is False
    report = capsys.readouterr()
    assert f"note    {choice['note']}" in report.out + report.err
    assert "record a run on a day of another air temperature" in choice["note"]
