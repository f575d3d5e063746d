"""A configuration of the wrong kind, or a key outside any table, is named for what it is."""

from pathlib import Path

from groupfit.cli import main

ROOT = Path(__file__).resolve().parents[1]


def refusal(capsys, *argv) -> str:
    assert main(list(argv)) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    return err


def test_a_scenario_given_to_fit_is_named_a_scenario(tmp_path, capsys):
    err = refusal(capsys, "fit", str(ROOT / "configs" / "paper_cycle.toml"), "--out", str(tmp_path / "o"))
    assert "kind = 'headstock' at the top level: a scenario configuration for groupfit simulate" in err
    assert not (tmp_path / "o").exists()


def test_a_key_above_every_table_is_named_a_key(tmp_path, capsys):
    config = tmp_path / "run.toml"
    config.write_text(f'p = 3\n[data]\npath = "{ROOT / "datasets" / "paper_cycle.csv"}"\n')
    err = refusal(capsys, "fit", str(config), "--out", str(tmp_path / "o"))
    assert "key 'p' at the top level: every key belongs in a table" in err and "unknown table" not in err


def test_a_run_configuration_given_to_simulate_is_named_a_run_configuration(tmp_path, capsys):
    err = refusal(capsys, "simulate", str(ROOT / "configs" / "default.toml"), "-o", str(tmp_path / "w.csv"))
    assert "a run configuration ([compare], [data], [model], [output], [search]), not a scenario" in err
    assert not (tmp_path / "w.csv").exists()
