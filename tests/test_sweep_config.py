import shutil
from pathlib import Path

import pytest

from groupfit.errors import InputError
from groupfit.sweep.config import read_study, spec_hash

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "datasets" / "synthetic_cycle.csv"


def write(tmp_path, text, name="study.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def data_line(path=DATA):
    return f'[data]\npath = "{Path(path).as_posix()}"\n'


def test_grid_expands_to_every_combination_and_ga_settings_only_for_ga(tmp_path):
    study = read_study(
        write(
            tmp_path,
            data_line()
            + """
[grid]
p = {start = 1, stop = 3}
n = [1, 3]
search = ["exact", "ga"]
[ga]
seed = {start = 0, stop = 4, step = 2}
max_generations = [20, 80]
""",
        )
    )
    exact = [r for r in study.runs if r.spec["search"]["method"] == "exact"]
    ga = [r for r in study.runs if r.spec["search"]["method"] == "ga"]
    assert len(exact) == 3 * 2
    assert len(ga) == 3 * 2 * 3 * 2
    assert exact[0].spec["search"] == {"method": "exact"}
    assert sorted({r.spec["search"]["seed"] for r in ga}) == [0, 2, 4]
    assert sorted({r.spec["model"]["p"] for r in study.runs}) == [1, 2, 3]
    assert len({r.run_hash for r in study.runs}) == len(study.runs)
    assert all(r.run_hash == spec_hash(r.spec) for r in study.runs)
    assert study.runs[0].spec["sensors"] == {"names": ["T1", "T2", "T3", "T4"]}


def test_p_zero_ga_is_the_exact_run_and_appears_once(tmp_path):
    study = read_study(
        write(
            tmp_path,
            data_line()
            + """
[grid]
p = [0, 1]
search = ["exact", "ga"]
[ga]
seed = [0, 1, 2]
""",
        )
    )
    at_zero = [r for r in study.runs if r.spec["model"]["p"] == 0]
    assert len(at_zero) == 1 and at_zero[0].spec["search"]["method"] == "exact"
    assert len(study.runs) == 1 + 1 + 3


def test_float_ranges_scalars_and_defaults(tmp_path):
    study = read_study(
        write(
            tmp_path,
            data_line()
            + """
[grid]
c = {start = 2.0, stop = 3.0, step = 0.5}
p = 2
""",
        )
    )
    assert [r.spec["model"]["c"] for r in study.runs] == [2.0, 2.5, 3.0]
    model = study.runs[0].spec["model"]
    assert model["p"] == 2 and model["n"] == 3 and model["objective"] == "sae" and model["intercept"] is True
    assert study.name == "study" and study.db is None


def test_relative_data_path_and_db_resolve_against_the_config_folder(tmp_path):
    folder = tmp_path / "configs"
    (tmp_path / "data").mkdir()
    folder.mkdir()
    shutil.copy(DATA, tmp_path / "data" / "run.csv")
    study = read_study(write(folder, '[study]\ndb = "out/s.sqlite"\n[data]\npath = "../data/run.csv"\n'))
    assert Path(study.runs[0].path) == (tmp_path / "data" / "run.csv").resolve()
    assert study.db == (folder / "out" / "s.sqlite").resolve()
    assert study.runs[0].dataset == "run"


def test_changed_data_changes_every_run_hash(tmp_path):
    copy = tmp_path / "run.csv"
    shutil.copy(DATA, copy)
    config = write(tmp_path, data_line(copy) + "[grid]\np = [1, 2]\n")
    before = [r.run_hash for r in read_study(config).runs]
    lines = copy.read_text().splitlines()
    lines[5] = lines[5].replace(lines[5].split(",")[-2], "9.999")
    copy.write_text("\n".join(lines) + "\n")
    after = [r.run_hash for r in read_study(config).runs]
    assert len(before) == len(after) == 2 and not set(before) & set(after)
    moved = tmp_path / "moved.csv"
    shutil.copy(copy, moved)
    assert [
        r.run_hash for r in read_study(write(tmp_path, data_line(moved) + "[grid]\np = [1, 2]\n", "m.toml")).runs
    ] == after


def test_sensor_options_resolve_per_data_set(tmp_path):
    study = read_study(
        write(
            tmp_path,
            data_line()
            + """
[grid]
p = 1
sensors = ["all", ["T1", "T3"], {select = "forward", k = 2}, {select = "lasso", k = 3, folds = 4}]
""",
        )
    )
    specs = [r.spec["sensors"] for r in study.runs]
    assert specs[0] == {"names": ["T1", "T2", "T3", "T4"]}
    assert specs[1] == {"names": ["T1", "T3"]}
    assert specs[2] == {
        "select": "forward",
        "k": 2,
        "candidates": ["T1", "T2", "T3", "T4"],
        "folds": 5,
        "cluster_corr": 0.98,
    }
    assert specs[3]["folds"] == 4 and specs[3]["k"] == 3


def test_single_name_list_is_one_subset_and_patterns_pick_candidates(tmp_path):
    study = read_study(
        write(
            tmp_path,
            f'[data]\npath = "{DATA.as_posix()}"\ntemps = ["T[13]", "T4"]\n[grid]\np = 1\nsensors = ["T1", "T2"]\n',
        )
    )
    assert [r.spec["sensors"] for r in study.runs] == [{"names": ["T1", "T2"]}]
    study = read_study(
        write(tmp_path, f'[data]\npath = "{DATA.as_posix()}"\ntemps = ["T[13]", "T4"]\n[grid]\np = 1\n', "b.toml")
    )
    assert study.runs[0].spec["sensors"] == {"names": ["T1", "T3", "T4"]}


@pytest.mark.parametrize(
    "body, words",
    [
        ("[grid]\npee = [1]\n", ["unknown key 'pee' in [grid]"]),
        ("[grids]\np = 1\n", ["unknown table [grids]"]),
        ("[ga]\nseeds = [1]\n", ["unknown key 'seeds' in [ga]"]),
        ("[grid]\np = {start = 0, end = 3}\n", ["[grid] p", "unknown key 'end'"]),
        ("[grid]\np = {start = 3, stop = 1}\n", ["[grid] p", "below start"]),
        ("[grid]\np = [1, -1]\n", ["[grid] p", "-1"]),
        ('[grid]\nobjective = ["mae"]\n', ["[grid] objective", "sae, sse"]),
        ('[grid]\nsearch = "pso"\n', ["[grid] search"]),
        ('[grid]\nsensors = [["T1", "T9"]]\n', ["sensors", "'T9'"]),
        ('[grid]\nsensors = [{select = "magic", k = 2}]\n', ["select = 'magic'"]),
        ('[grid]\nsensors = [{select = "lasso", k = 9}]\n', ["k = 9", "4 candidate"]),
        ('[grid]\nsensors = [{select = "lasso", k = 2, alpha = 1}]\n', ["unknown key 'alpha'"]),
        ("[ga]\npopulation_size = [1]\n", ["[ga] population_size"]),
        ('[study]\ncertify = "maybe"\n', ["certify"]),
    ],
)
def test_bad_studies_name_the_key(tmp_path, body, words):
    config = write(tmp_path, data_line() + body)
    with pytest.raises(InputError) as error:
        read_study(config)
    message = str(error.value)
    assert "study.toml" in message
    for word in words:
        assert word in message


def test_missing_data_file_and_missing_data_table(tmp_path):
    with pytest.raises(InputError, match="nothere.csv"):
        read_study(write(tmp_path, '[data]\npath = "nothere.csv"\n'))
    with pytest.raises(InputError, match=r"no data"):
        read_study(write(tmp_path, "[grid]\np = 1\n", "b.toml"))


def test_several_data_sets_each_get_every_run(tmp_path):
    (tmp_path / "a").mkdir()
    shutil.copy(DATA, tmp_path / "a" / "first.csv")
    (tmp_path / "second.csv").write_text(DATA.read_text().replace("21.63394", "21.63395"))
    study = read_study(write(tmp_path, '[data]\npaths = ["a/first.csv", "second.csv"]\n[grid]\np = [1, 2]\n'))
    assert [r.dataset for r in study.runs] == ["first", "first", "second", "second"]
    assert len({r.run_hash for r in study.runs}) == 4
    # the same bytes under another name are the same runs, and run once
    shutil.copy(DATA, tmp_path / "third.csv")
    study = read_study(write(tmp_path, '[data]\npaths = ["a/first.csv", "third.csv"]\n[grid]\np = [1, 2]\n', "b.toml"))
    assert [r.dataset for r in study.runs] == ["first", "first"]
    shutil.copy(DATA, tmp_path / "a" / "second.csv")
    with pytest.raises(InputError, match="two data files are named 'second'"):
        read_study(write(tmp_path, '[data]\npaths = ["a/second.csv", "second.csv"]\n', "dup.toml"))


@pytest.mark.parametrize("name", ["paper_sweep", "sweep_sensors", "sweep_soft_offset"])
def test_shipped_studies_read(name):
    study = read_study(ROOT / "configs" / f"{name}.toml")
    assert study.runs and all(Path(run.path).is_file() for run in study.runs)
    exact_p = sorted(r.spec["model"]["p"] for r in study.runs if r.spec["search"]["method"] == "exact")
    assert set(range(5)) <= set(exact_p)
