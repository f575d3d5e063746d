"""An ambient logged under a machine sensor's name (``T0``), declared with ``diagnose --ambient``."""

import dataclasses

import pytest
from support import independent_machine as machine
from support.bench_modules import load
from support.diagnose_scenarios import TEMPS, lumped, with_ambient_effect

from groupfit.cli import main
from groupfit.diagnose import diagnose
from groupfit.diagnose.notes import AMBIENT
from groupfit.runtime import replay_groups

bench = load("bench_diagnose_independent")


def renamed_ambient(scenario, name="T0"):
    """The same scenario with its air column logged as ``name``."""
    rename = {"T_amb": name}
    return dataclasses.replace(
        scenario,
        modelling=scenario.modelling.rename(columns=rename),
        validation=scenario.validation.rename(columns=rename),
        missing=tuple(rename.get(c, c) for c in scenario.missing),
    )


def test_a_declared_ambient_is_diagnosed_as_the_named_one():
    """Independent machine, an unsensed part that follows the air: the air as ``T_amb`` is the truth to match."""
    scenario = machine.random_scenarios(1, 25, "absolute")[0]
    assert scenario.missing == ("T_amb",)

    def run(s, **kwargs):
        model, modelling, validation = bench.base_model(s, "none")
        return diagnose(model, modelling, validation, live_rule=replay_groups, **kwargs)

    named = run(scenario)
    logged_as_t0 = renamed_ambient(scenario)
    undeclared = run(logged_as_t0)
    declared = run(logged_as_t0, ambient=["T0"])

    first = named.added[0].feature
    assert first.column == "T_amb" and first.transform == "lowpass"
    # read as a machine sensor, T0 is only tried as measured, and the report says how to declare it
    assert all(c.feature.transform == "identity" for c in undeclared.added if c.feature.column == "T0")
    said = undeclared.notes_of(AMBIENT)
    assert any("unused sensors (T0) were read as machine sensors" in n and "--ambient" in n for n in said)
    assert not named.notes_of(AMBIENT) and not declared.notes_of(AMBIENT)
    # declared, it is the ambient: the same effect, the same validation, named as the ambient
    assert [dataclasses.replace(c.feature, column="T_amb") for c in declared.added] == [c.feature for c in named.added]
    assert declared.after["validate"]["rms_um"] == pytest.approx(named.after["validate"]["rms_um"], rel=1e-9)
    assert declared.after["validate"]["rms_um"] <= 0.6 * declared.before["validate"]["rms_um"]
    assert declared.summary().startswith("missing effect: ambient temperature `T0`, low-pass")
    assert undeclared.after["validate"]["rms_um"] > 2 * declared.after["validate"]["rms_um"]


@pytest.mark.parametrize(
    "column, words",
    [
        ("nope", "--ambient column 'nope' not found; columns: time_s"),
        ("T1", "the model reads 'T1' as an input"),
        ("T_amb,T_amb", "names 'T_amb' twice; name each column once"),
    ],
)
def test_a_wrong_ambient_column_is_one_line_and_exit_2(tmp_path, capsys, column, words):
    data = tmp_path / "run.csv"
    with_ambient_effect(lumped(seed=0)).to_csv(data, index=False)
    fit = ["fit", "--data", str(data), "--temps", ",".join(TEMPS), "--p", "0", "--reference", "none", "--quiet"]
    assert main([*fit, "--out", str(tmp_path / "model")]) == 0
    capsys.readouterr()
    out = tmp_path / "d"
    argv = ["diagnose", str(tmp_path / "model" / "model.json"), "--data", str(data), "--ambient", column]
    try:
        code = main([*argv, "--out", str(out)])
    except SystemExit as exc:  # refused by argparse as it reads the option
        code = exc.code
    error = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(error) == 1 and words in error[0]
    assert not out.exists()


@pytest.mark.parametrize("value", ["1e300", "200", "0", "-1", "nan"])
def test_a_heat_law_exponent_out_of_range_is_refused_as_the_option_is_read(capsys, value):
    """1e300 overflowed at every speed and silently turned a found heat law into 'T3 as measured'."""
    with pytest.raises(SystemExit) as stop:
        main(["diagnose", "model.json", "--data", "run.csv", "--heat-exponent", value])
    err = capsys.readouterr().err.strip().splitlines()
    assert stop.value.code == 2 and "--heat-exponent" in err[-1] and value in err[-1]
    assert "must be > 0 and at most 10" in err[-1] or "give a number" in err[-1]
