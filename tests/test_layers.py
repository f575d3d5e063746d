"""The layers: what the light entry points import, and the model file as one typed object."""

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.model import FORMAT, ModelFile

HEAVY = ("sklearn", "deap")


def imported_after(code: str) -> set[str]:
    """Top-level packages loaded by ``code`` in a fresh interpreter."""
    probe = f"{code}\nimport sys, json\nprint(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}})))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


@pytest.mark.cli
def test_groupfit_help_imports_neither_sklearn_nor_deap():
    loaded = imported_after("from groupfit.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass")
    assert "groupfit" in loaded and not loaded & set(HEAVY)


@pytest.mark.cli
def test_exports_depend_on_the_runtime_not_on_the_fitting_stack():
    loaded = imported_after(
        "import groupfit.export.json_table, groupfit.export.c, groupfit.export.st, groupfit.runtime"
    )
    assert not loaded & set(HEAVY)


@pytest.mark.cli
def test_a_verb_imports_only_what_it_needs():
    loaded = imported_after(
        "from groupfit.cli import main\ntry:\n    main(['export', '--help'])\nexcept SystemExit:\n    pass"
    )
    assert not loaded & set(HEAVY)


def small_model() -> dict:
    return {
        "format": FORMAT,
        "sampling_period_s": 100.0,
        "temps": ["A", "B"],
        "error": "error_um",
        "intercept": True,
        "objective": "sae",
        "p": 1,
        "n": 3,
        "c": 3.0,
        "breaks": [10],
        "soft_groups": [[1, 10], [8, 20]],
        "coefficients": [[1.0, 2.0, 0.5], [5.0, -1.0, 0.25]],
        "objective_value": 0.0,
        "switching": {"criterion": "A", "criterion_index": 0, "criterion_series": [float(v) for v in range(20)]},
    }


def test_model_file_round_trips_and_keeps_keys_it_does_not_know(tmp_path):
    data = {**small_model(), "reference_temperature_c": 20.0}
    model = ModelFile.from_dict(data)
    assert model.n_samples is None and model.derived_inputs is None  # optional keys of older files
    assert model.extra == {"reference_temperature_c": 20.0}
    assert model.to_dict() == data
    model.save(tmp_path / "m.json")
    assert json.loads((tmp_path / "m.json").read_text()) == data
    assert ModelFile.load(tmp_path / "m.json") == model


def test_model_file_predicts_by_serving_group():
    model = ModelFile.from_dict(small_model())
    inputs = [[1.0, 2.0]] * 12
    groups = model.serving_groups(12)
    assert groups.tolist() == [0] * 7 + [1] * 5  # the overlap 8…10 is served by group 2
    prediction = model.predict(inputs)
    assert prediction[0] == 1.0 + 2.0 * 1.0 + 0.5 * 2.0 and prediction[-1] == 5.0 - 1.0 + 0.25 * 2.0


def test_model_file_names_what_is_wrong(tmp_path):
    broken = {**small_model(), "coefficients": [[1.0, 2.0]]}
    with pytest.raises(InputError, match="'breaks' and 'coefficients' do not match p = 1"):
        ModelFile.from_dict(broken)
    path = tmp_path / "m.json"
    path.write_text(json.dumps({"format": "other"}))
    with pytest.raises(InputError, match=f"{path}: not a {FORMAT} model file"):
        ModelFile.load(path)


def test_out_is_the_one_name_for_outputs_and_old_spellings_still_work(tmp_path, capsys):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(small_model()))
    assert main(["export", str(model), "--target", "json", "--out", str(tmp_path / "a")]) == 0
    assert main(["export", str(model), "--target", "json", "-o", str(tmp_path / "b")]) == 0
    assert main(["export", str(model), "--target", "json", "--output", str(tmp_path / "c")]) == 0
    assert [(tmp_path / d / "groupfit_runtime.json").is_file() for d in "abc"] == [True] * 3
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["export", "--help"])
    shown = capsys.readouterr().out
    assert "--out DIR" in shown and "-o" not in shown.split() and "--output" not in shown
    with pytest.raises(SystemExit) as exit_info:
        main(["export", str(model), "--target", "json"])
    assert exit_info.value.code == 2 and "--out" in capsys.readouterr().err


def test_the_packaged_default_configuration_names_packaged_data():
    from pathlib import Path

    from groupfit.config import PACKAGED_DEFAULT, read_config

    config = read_config(PACKAGED_DEFAULT)  # in a checkout the packaged files link to configs/ and datasets/
    names = [Path(path).name for path in [config.data.path, *config.data.validate]]
    assert names == [
        "paper_cycle.csv",
        "repeat_timing.csv",
        "repeat_ambient25.csv",
        "repeat_warm.csv",
        "validation_speed.csv",
        "validation_timing.csv",
    ]
    assert all((PACKAGED_DEFAULT.parents[1] / "datasets" / name).is_file() for name in names)


def own_imports(package: str) -> dict[str, set[str]]:
    """For every module of ``groupfit.<package>``, the project's modules it imports (at any depth of its code)."""
    root = Path(__file__).resolve().parents[1] / "groupfit" / package
    found = {}
    for path in sorted(root.rglob("*.py")):
        names = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("groupfit"):
                names.add(node.module)
            elif isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names if alias.name.startswith("groupfit"))
        found[str(path.relative_to(root.parent))] = names
    return found


def test_held_out_validation_imports_no_command_no_diagnosis_and_no_sweep():
    forbidden = ("groupfit.commands", "groupfit.cli", "groupfit.diagnose", "groupfit.sweep", "groupfit.comparison")
    offenders = {
        module: sorted(name for name in names if name.startswith(forbidden))
        for module, names in own_imports("heldout").items()
    }
    assert len(offenders) >= 5 and not any(offenders.values()), offenders
