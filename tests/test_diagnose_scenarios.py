"""The diagnosis on FE data sets with one undeclared effect each (configs/diag_*.toml)."""

import pytest

from groupfit.model import ModelFile

TEMPS = "T1,T2,T3,T4"
EXPECTED = {
    "ambient": {"T_amb"},
    "source": {"src_zscrew_on"},
    "lag": {"spindle_on", "speed_rpm"},  # a low-pass of a heat proxy
    "speed": {"speed_rpm"},  # several speeds: the bearing-heat law of the speed, low-passed
}


@pytest.mark.parametrize("scenario", sorted(EXPECTED))
def test_the_undeclared_effect_is_named_and_validation_rms_falls_40_percent(diagnosed_scenario, scenario):
    result, _, report = diagnosed_scenario(scenario)
    assert result["added"], f"{scenario}: nothing found"
    first = result["added"][0]
    assert first["column"] in EXPECTED[scenario]
    assert first["transform"] in ("lowpass", "identity", "delay")
    before, after = result["before"]["validate"]["rms_um"], result["after"]["validate"]["rms_um"]
    assert after <= 0.6 * before and result["improved"] is True
    assert "missing effect" in report
    augmented = ModelFile.load(result["model"]).to_dict()
    assert augmented["temps"][:4] == TEMPS.split(",") and augmented["derived_inputs"][0]["column"] == first["column"]


def test_lag_scenario_finds_the_time_constant_of_the_unsensed_part(diagnosed_scenario):
    result, _, _ = diagnosed_scenario("lag")
    # configs/diag_lag_*.toml: the unsensed part lags the bearing heat with tau = 6 h
    assert result["added"][0]["tau_s"] == pytest.approx(6 * 3600.0, rel=0.35)


def test_speed_scenario_finds_the_heat_law_and_the_time_constant(diagnosed_scenario):
    result, _, _ = diagnosed_scenario("speed")
    # configs/diag_speed_*.toml: bearing heat ∝ speed^(5/3), the unsensed part lags it with tau = 1.5 h
    first = result["added"][0]
    assert first["exponent"] == pytest.approx(5 / 3) and first["tau_s"] == pytest.approx(1.5 * 3600.0, rel=0.35)


def test_nothing_missing_on_the_clean_machine(diagnosed_scenario):
    result, model_path, report = diagnosed_scenario("none")
    assert result["added"] == [] and result["model"] == str(model_path)
    assert "nothing missing" in report
