"""The typed run settings: a TOML configuration and the command line's options end in one frozen object."""

from __future__ import annotations

import dataclasses
import json
import tomllib
from pathlib import Path

import pytest

from groupfit.cli import main
from groupfit.comparison import ComparisonSettings
from groupfit.config import read_config
from groupfit.search.base import DEFAULT_SEED, GA_DEFAULTS
from groupfit.settings import CompareSettings, DataSettings, ModelSettings, RunSettings

ROOT = Path(__file__).resolve().parents[1]


def test_a_configuration_is_read_into_the_settings_with_the_defaults_elsewhere():
    path = ROOT / "configs" / "default.toml"
    tables = tomllib.loads(path.read_text(encoding="utf-8"))
    settings = read_config(path)
    assert Path(settings.data.path) == (path.parent / tables["data"]["path"]).resolve()
    assert [Path(p).name for p in settings.data.validate] == [Path(p).name for p in tables["data"]["validate"]]
    assert settings.data.temps == tuple(tables["data"]["temps"])
    for key, value in tables["model"].items():
        assert getattr(settings.model, key) == value
    assert settings.model.p == ModelSettings().p == "auto"  # not in the file: the default
    assert settings.search.method == tables["search"]["method"] and settings.search.seed == tables["search"]["seed"]
    assert settings.search.ga == GA_DEFAULTS
    assert settings.output_dir == tables["output"]["dir"]
    assert settings.compare.conditions == tuple(tables["compare"]["conditions"])
    assert "heat_exponent" not in tables["compare"]
    assert settings.compare.heat_exponent == 5 / 3  # exactly as fit --model ar1 takes it
    assert settings.compare.ar1_start == CompareSettings().ar1_start


def test_options_given_replace_fields_and_options_not_given_leave_them():
    settings = RunSettings()
    given = settings.given(
        data={"time": "t", "temps": ["A", "B"], "error": None},
        model={"p": 2, "pmax": None},
        search={"seed": 7, "population_size": 12, "certify": None},
        output={"dir": "elsewhere"},
    )
    assert given.data == dataclasses.replace(DataSettings(), time="t", temps=("A", "B"))
    assert given.model == dataclasses.replace(ModelSettings(), p=2)
    assert given.search.seed == 7 and given.search.certify == settings.search.certify
    assert given.search.ga == dataclasses.replace(GA_DEFAULTS, population_size=12)
    assert given.output_dir == "elsewhere" and given.compare == settings.compare
    assert settings == RunSettings()  # frozen: the original is unchanged
    with pytest.raises(dataclasses.FrozenInstanceError):
        given.model.p = 3  # type: ignore[misc]


def test_a_run_on_the_command_line_drops_the_configured_inputs_and_validation_runs():
    settings = read_config(ROOT / "configs" / "default.toml").without_default_runs()
    assert settings.data.temps is None and settings.data.validate == ()
    assert settings.data.path is not None  # the path is replaced by --data, not dropped


def test_each_default_is_written_once():
    comparison = ComparisonSettings()
    for field in dataclasses.fields(CompareSettings):
        if hasattr(comparison, field.name):
            assert getattr(comparison, field.name) == getattr(CompareSettings(), field.name), field.name
    assert (comparison.n, comparison.c, comparison.objective, comparison.fit_intercept, comparison.fit_pmax) == (
        ModelSettings().n,
        ModelSettings().c,
        ModelSettings().objective,
        ModelSettings().intercept,
        ModelSettings().pmax,
    )
    assert RunSettings().search.seed == DEFAULT_SEED
    source = (ROOT / "groupfit" / "config.py").read_text(encoding="utf-8")
    assert "DEFAULTS" not in source  # the reader holds no second copy of the defaults


def test_the_seed_walks_from_the_command_line_to_the_search(tmp_path):
    """``--seed`` → the settings → the estimator → the GA; the model file records the seed searched with."""
    data = ROOT / "datasets" / "paper_cycle.csv"
    seeds = {}
    for seed in (3, 11):
        out = tmp_path / str(seed)
        args = ["fit", "--data", str(data), "--temps", "T1,T2", "--p", "2", "--seed", str(seed), "--quiet"]
        assert main([*args, "--out", str(out), "--json", str(out / "fit.json")]) == 0
        seeds[seed] = json.loads((out / "fit.json").read_text(encoding="utf-8"))["search"]["seed"]
    assert seeds == {3: 3, 11: 11}
