"""No command writes to a path it read, replaces a data file without --force, or leaves part of its outputs.

Every verb with an output option is run in process with that output naming
one of its inputs (as given, through a symbolic link, and through a hard
link): each must exit 2 with one line and leave every file as it was.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import stat

import matplotlib
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC, synthetic_model

import groupfit.commands.simulate as simulate_command
from groupfit.cli import main
from groupfit.errors import InputError
from groupfit.io import atomic_write_text, note_read, save_figure
from groupfit.outputs import OutputPlan

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SCREW_RUN = SYNTHETIC.parent / "screw_A.csv"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plan_inputs")
    pd.read_csv(SYNTHETIC).iloc[:200].to_csv(folder / "run.csv", index=False)
    pd.read_csv(SYNTHETIC).iloc[:100].to_csv(folder / "run0.csv", index=False)
    model, _ = synthetic_model(p=3, n=3)
    (folder / "model.json").write_text(json.dumps(model))
    (folder / "model_augmented.json").write_text(json.dumps(model))
    (folder / "lumped.toml").write_text('kind = "lumped"\nn_samples = 50\n')
    (folder / "fit.toml").write_text(f'[data]\npath = "{(folder / "run.csv").as_posix()}"\ntemps = ["T1", "T2"]\n')
    (folder / "sweep.toml").write_text(f'[data]\npath = "{(folder / "run.csv").as_posix()}"\n[grid]\np = [1]\n')
    (folder / "screw_model.json").write_text('{"format": "groupfit-screw-model/1"}\n')
    if SCREW_RUN.exists():
        shutil.copy(SCREW_RUN, folder / "screw_A.csv")
    return folder


def _fit(*extra):
    return ("fit", "--quiet", "--data", "{in}/run.csv", "--temps", "T1,T2", "--p", "1", "--out", "{tmp}/o", *extra)


# (verb and options, the input the output names); {in} is the inputs folder, {tmp} the test's own
CLOBBERS = [
    (_fit("--json", "{in}/run.csv"), "run.csv"),
    (("fit", "{in}/fit.toml", "--quiet", "--json", "{in}/fit.toml", "--out", "{tmp}/o"), "fit.toml"),
    (("fit", "{in}/fit.toml", "--quiet", "--json", "{in}/run.csv", "--out", "{tmp}/o"), "run.csv"),
    (("diagnose", "{in}/model_augmented.json", "--data", "{in}/run.csv", "--out", "{in}"), "model_augmented.json"),
    (
        (
            "compare",
            "--quiet",
            "--data",
            "{in}/run.csv",
            "--temps",
            "T1,T2",
            "--json",
            "{in}/run.csv",
            "--out",
            "{tmp}/o",
        ),
        "run.csv",
    ),
    (("diagnose", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{in}/run.csv", "--out", "{tmp}"), "run.csv"),
    (
        ("diagnose", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{in}/model.json", "--out", "{tmp}"),
        "model.json",
    ),
    (("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{in}/model.json"), "model.json"),
    (("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{in}/run.csv"), "run.csv"),
    (
        (
            "replay",
            "{in}/model.json",
            "--data",
            "{in}/run.csv",
            "--continues",
            "{in}/run0.csv",
            "--json",
            "{in}/run0.csv",
        ),
        "run0.csv",
    ),
    (("simulate", "{in}/lumped.toml", "--out", "{in}/lumped.toml", "--force"), "lumped.toml"),
    (("sweep", "{in}/sweep.toml", "--db", "{tmp}/s.sqlite", "--json", "{in}/sweep.toml", "--quiet"), "sweep.toml"),
    (("sweep", "{in}/sweep.toml", "--db", "{in}/run.csv", "--quiet"), "run.csv"),
    (("iso230", "{in}/run.csv", "--json", "{in}/run.csv"), "run.csv"),
    (
        ("replay", "{in}/screw_model.json", "--data", "{in}/run.csv", "--json", "{in}/screw_model.json"),
        "screw_model.json",
    ),
    (("screw", "predict", "{in}/screw_model.json", "--data", "{in}/run.csv", "--json", "{in}/run.csv"), "run.csv"),
    (("screw", "identify", "{in}/screw_A.csv", "--json", "{in}/screw_A.csv", "--out", "{tmp}"), "screw_A.csv"),
    (("screw", "compare", "{in}/screw_A.csv", "--validate", "{in}/run.csv", "--json", "{in}/run.csv"), "run.csv"),
]
IDS = [" ".join(a[:2]) + " → " + name for a, name in CLOBBERS]


def _snapshot(*folders):
    return {p: (p.stat().st_size, p.stat().st_mtime_ns) for f in folders for p in f.rglob("*")}


def _contents(*folders):
    """Every file's bytes: a refusal when the outputs are committed leaves the files as they were (the folders'
    times change with the temporary files made and removed beside the targets)."""
    return {p: p.read_bytes() for f in folders for p in f.rglob("*") if p.is_file()}


def _run(argv, inputs, tmp_path, capsys):
    argv = [a.replace("{in}", str(inputs)).replace("{tmp}", str(tmp_path)) for a in argv]
    before = _snapshot(inputs, tmp_path)
    capsys.readouterr()
    try:
        status = main(argv)
    except SystemExit as exc:
        status = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    return status, err, before == _snapshot(inputs, tmp_path)


@pytest.mark.parametrize("link", ["as given", "symbolic link", "hard link", "through a link and .."])
@pytest.mark.parametrize("argv, name", CLOBBERS, ids=IDS)
def test_no_command_writes_to_a_path_it_read(inputs, tmp_path, capsys, argv, name, link):
    if "screw_A.csv" in " ".join(argv) and not (inputs / "screw_A.csv").exists():
        pytest.skip("the shipped ball-screw run is not there")
    if link != "as given":
        # the output names the input under another name: a link beside the inputs, pointing at it
        named = [i for i, a in enumerate(argv) if a == f"{{in}}/{name}" and argv[i - 1] in ("--json", "--db", "--out")]
        if not named:
            pytest.skip("the output is a folder: the file it would replace is named by the verb")
        alias = inputs / f"alias_{tmp_path.name}{(inputs / name).suffix}"
        if link == "through a link and ..":
            # tmp/link → inputs/deep, so tmp/link/../name is inputs/name, though the text reads tmp/name
            (inputs / f"deep_{tmp_path.name}").mkdir()
            alias = tmp_path / "link"
            os.symlink(inputs / f"deep_{tmp_path.name}", alias)
            named_as = f"{alias}/../{name}"
        else:
            (os.symlink if link == "symbolic link" else os.link)(inputs / name, alias)
            named_as = str(alias)
        last = named[-1]
        argv = (*argv[:last], named_as, *argv[last + 1 :])
    try:
        status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    finally:
        if link != "as given":
            alias.unlink()
        if link == "through a link and ..":
            (inputs / f"deep_{tmp_path.name}").rmdir()
    assert status == 2 and len(err) == 1, err
    assert "a file this command reads" in err[0] and name in err[0], err[0]
    assert unchanged


def test_an_existing_data_file_is_replaced_only_with_force(inputs, tmp_path, capsys):
    (tmp_path / "old.csv").write_text("time_s,T1\n0,20\n")
    argv = ("simulate", "{in}/lumped.toml", "--out", "{tmp}/old.csv")
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and "--force" in err[0] and unchanged
    status, err, unchanged = _run((*argv, "--force"), inputs, tmp_path, capsys)
    assert status == 0 and not unchanged
    assert len(pd.read_csv(tmp_path / "old.csv")) == 50
    # the same for --json naming an existing table that is not an input
    argv = ("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{tmp}/old.csv")
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and "--force" in err[0] and unchanged
    for suffix in (".mat", ".ods", ".xlsm"):  # every kind a run is read from
        (tmp_path / f"old{suffix}").write_bytes(b"a run of the user's")
        argv = ("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", f"{{tmp}}/old{suffix}")
        status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
        assert status == 2 and "would replace an existing data file" in err[0] and unchanged, suffix
        assert (tmp_path / f"old{suffix}").read_bytes() == b"a run of the user's"


def test_an_existing_model_file_is_replaced_only_with_force(inputs, tmp_path, capsys):
    model = (inputs / "model.json").read_text()
    (tmp_path / "kept.json").write_text(model)
    argv = ("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{tmp}/kept.json")
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and "would replace a model file" in err[0] and "--force" in err[0]
    assert unchanged
    status, _, _ = _run((*argv, "--force"), inputs, tmp_path, capsys)
    assert status == 0 and "rms_um" in json.loads((tmp_path / "kept.json").read_text())
    # a JSON file that is not a model (last run's report) is replaced as before
    status, _, _ = _run(argv, inputs, tmp_path, capsys)
    assert status == 0
    # fit's --json is a model file itself: running fit again replaces it, a report over it is refused
    for _ in range(2):
        assert _run(_fit("--json", "{tmp}/fit.json"), inputs, tmp_path, capsys)[0] == 0
    status, err, unchanged = _run((*argv[:-1], "{tmp}/fit.json"), inputs, tmp_path, capsys)
    assert status == 2 and "would replace a model file" in err[0] and unchanged


@pytest.mark.parametrize(
    "argv, words",
    [
        (_fit("--json", "{tmp}/o/model.json"), "--json writes too"),
        (("simulate", "{in}/lumped.toml", "--out", "{tmp}/run.png"), "--out writes too"),
        (
            ("sweep", "{in}/sweep.toml", "--quiet", "--db", "{tmp}/s.sqlite", "--out", "{tmp}/s.sqlite"),
            "--db names the folder --out writes into",
        ),
        (
            ("sweep", "{in}/sweep.toml", "--quiet", "--db", "{tmp}/s", "--out", "{tmp}/s/report"),
            "--db names the folder --out writes into",
        ),
        (_fit("--json", "{tmp}/o"), "--out names the file --json writes"),
    ],
    ids=["fit --json over the model", "simulate --out over its figure", "sweep --db is --out", "--out in --db", "fit"],
)
def test_two_outputs_may_not_name_one_file(inputs, tmp_path, capsys, argv, words):
    """Refused before any work: nothing is written (a sweep's study is not run, its database not made)."""
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and words in err[0] and unchanged, err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv",
    [
        _fit("--out", ""),
        ("export", "{in}/model.json", "--target", "c", "--out", ""),
        ("simulate", "{in}/lumped.toml", "--out", ""),
        ("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", ""),
    ],
    ids=["fit", "export", "simulate", "replay --json"],
)
def test_an_empty_output_path_is_refused(inputs, tmp_path, capsys, argv):
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and "empty path" in err[0] and unchanged


@pytest.mark.parametrize(
    "argv, words",
    [
        (_fit("--out", "-"), "--out -: names a folder of files, which cannot go to stdout"),
        (("export", "{in}/model.json", "--target", "c", "--out", "-"), "--out -: names a folder of files"),
        (("sweep", "{in}/sweep.toml", "--quiet", "--db", "-"), "--db -: the study's database is a file"),
    ],
    ids=["fit --out", "export --out", "sweep --db"],
)
def test_stdout_for_a_folder_or_a_database_is_refused_not_made_a_file_named_dash(
    inputs, tmp_path, capsys, monkeypatch, argv, words
):
    monkeypatch.chdir(tmp_path)
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and words in err[0] and unchanged, err
    assert not (tmp_path / "-").exists()


@pytest.mark.parametrize("verb", ["fit", "compare"])
def test_an_output_folder_from_the_configuration_is_named_as_such(inputs, tmp_path, capsys, verb):
    (tmp_path / "taken").write_text("a file where the folder would be\n")
    config = tmp_path / "run.toml"
    config.write_text(f'[data]\npath = "{inputs}/run.csv"\ntemps = ["T1", "T2"]\n[output]\ndir = "{tmp_path}/taken"\n')
    status, err, unchanged = _run((verb, str(config), "--quiet"), inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and unchanged, err
    assert err[0].endswith(f"choose another [output] dir of {config}")
    status, err, _ = _run((verb, str(config), "--quiet", "--out", "{tmp}/taken"), inputs, tmp_path, capsys)
    assert status == 2 and err[0].endswith("choose another --out")


@pytest.mark.parametrize(
    "argv, blocker",
    [
        (("export", "{in}/model.json", "--target", "all", "--out", "{tmp}/e"), "e/FB_GroupfitComp.st"),
        (_fit("--json", "{tmp}/r.json"), "o/fit.png"),
        (
            ("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", "{tmp}/r.json", "--out", "{tmp}/o"),
            "o/replay.png",
        ),
        (("simulate", "{in}/lumped.toml", "--out", "{tmp}/run.csv"), "run.png"),
    ],
    ids=["export", "fit", "replay", "simulate"],
)
def test_one_output_that_cannot_be_written_stops_every_output(inputs, tmp_path, capsys, argv, blocker):
    (tmp_path / blocker).mkdir(parents=True)
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and blocker.split("/")[-1] in err[0], err
    assert unchanged and [p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file()] == []


def test_the_plan_writes_all_or_none_and_refuses_what_was_read_on_the_way(tmp_path):
    read = tmp_path / "read.csv"
    read.write_text("a\n1\n")
    plan = OutputPlan()
    with pytest.raises(InputError, match="a file this command reads"):
        with plan.active():
            atomic_write_text(tmp_path / "first.json", "{}")
            note_read(read)  # a file read by a loader the verb did not declare
            atomic_write_text(read, "{}")
    assert read.read_text() == "a\n1\n" and sorted(p.name for p in tmp_path.iterdir()) == ["read.csv"]
    # a failure after staging (a figure, then an error) leaves nothing either
    figure = plt.figure()
    with pytest.raises(RuntimeError):
        with OutputPlan().active():
            save_figure(figure, tmp_path / "f.png")
            atomic_write_text(tmp_path / "new" / "x.json", "{}")
            atomic_write_text(tmp_path / "new" / "deeper" / "y.json", "{}")
            assert (tmp_path / "new" / "deeper").is_dir()  # made for the staged file
            raise RuntimeError("the work failed after the first outputs")
    plt.close(figure)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["read.csv"]  # no file, and no folder made for one
    with OutputPlan().active():
        atomic_write_text(tmp_path / "x.json", "{}")
        assert not (tmp_path / "x.json").exists()  # staged, not yet there
    assert (tmp_path / "x.json").read_text() == "{}"


@pytest.mark.parametrize(
    "name, content",
    [
        ("log.csv.gz", b"\x1f\x8b\x08\x00 a gzipped run"),
        ("log.dat", b"time_s;T1\n0;20\n"),
        ("study.sqlite", b"SQLite format 3\x00"),
        ("model_v2.bak", b"time,drift\n"),
        ("notes.txt", b"measured on the 3rd"),
    ],
)
def test_a_json_output_replaces_only_a_json_document_without_force(inputs, tmp_path, capsys, name, content):
    (tmp_path / name).write_bytes(content)
    argv = ("replay", "{in}/model.json", "--data", "{in}/run.csv", "--json", f"{{tmp}}/{name}")
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and "not a JSON result" in err[0] and "--force" in err[0] and unchanged
    assert _run((*argv, "--force"), inputs, tmp_path, capsys)[0] == 0
    assert "rms_um" in json.loads((tmp_path / name).read_text())
    # the report written, a run again replaces it; so it does an empty file
    assert _run(argv, inputs, tmp_path, capsys)[0] == 0
    (tmp_path / name).write_bytes(b"")
    assert _run(argv, inputs, tmp_path, capsys)[0] == 0


def test_a_model_output_replaces_only_a_model_of_its_own_kind(inputs, tmp_path, capsys):
    (tmp_path / "screw.json").write_text('{"format": "groupfit-ballscrew/1", "kind": "ballscrew"}\n')
    status, err, unchanged = _run(_fit("--json", "{tmp}/screw.json"), inputs, tmp_path, capsys)
    assert status == 2 and "a model file of another kind (groupfit-ballscrew)" in err[0] and unchanged
    assert _run(_fit("--json", "{tmp}/screw.json", "--force"), inputs, tmp_path, capsys)[0] == 0
    if not (inputs / "screw_A.csv").exists():
        pytest.skip("the shipped ball-screw run is not there")
    # fit wrote a grouped model there: screw identify's --json is refused over it
    argv = ("screw", "identify", "{in}/screw_A.csv", "--json", "{tmp}/screw.json", "--out", "{tmp}/s")
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and "a model file of another kind (groupfit-model)" in err[0] and unchanged


def test_sigterm_leaves_no_output_and_no_temporary_file(inputs, tmp_path, monkeypatch, capsys):
    """A verb stopped by SIGTERM (kill, timeout, a service stop) cleans up as one stopped by Ctrl-C."""

    def staged_then_terminated(args):
        atomic_write_text(tmp_path / "half.json", "{}")
        assert [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")] != []  # staged beside its target
        os.kill(os.getpid(), signal.SIGTERM)
        raise AssertionError("SIGTERM did not stop the verb")

    monkeypatch.setattr(simulate_command, "run_simulate", staged_then_terminated)
    previous = signal.getsignal(signal.SIGTERM)
    status = main(["simulate", str(inputs / "lumped.toml"), "--out", str(tmp_path / "x.csv")])
    assert status == 128 + signal.SIGTERM
    assert capsys.readouterr().err.strip() == "groupfit simulate: terminated"
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) == previous


def test_a_table_in_an_output_folder_is_replaced_only_by_one_with_its_header(tmp_path):
    folder = tmp_path / "report"
    folder.mkdir()
    earlier = "run_id,p,objective\n1,2,3.5\n"
    (folder / "runs.csv").write_text(earlier)
    plan = OutputPlan()
    plan.folder(folder, "--out", files=("runs.csv", "summary.md"))
    with plan.active():  # a run of the same study: the same header, replaced
        atomic_write_text(folder / "runs.csv", "run_id,p,objective\n1,2,3.4\n")
        atomic_write_text(folder / "summary.md", "# study\n")
    assert (folder / "runs.csv").read_text().endswith("3.4\n")

    users = "time_s,T1,error_um\n0,20.1,0.5\n"  # the user's own log of that name
    (folder / "runs.csv").write_text(users)
    (folder / "summary.md").unlink()
    plan = OutputPlan()
    plan.folder(folder, "--out", files=("runs.csv", "summary.md"))
    with pytest.raises(InputError, match=r"runs.csv: --out would replace a table that is not an earlier output"):
        with plan.active():
            atomic_write_text(folder / "runs.csv", "run_id,p,objective\n1,2,3.4\n")
            atomic_write_text(folder / "summary.md", "# study\n")
    assert (folder / "runs.csv").read_text() == users
    assert sorted(p.name for p in folder.iterdir()) == ["runs.csv"]  # nothing else written either
    plan = OutputPlan(force=True)
    plan.folder(folder, "--out", files=("runs.csv",))
    with plan.active():
        atomic_write_text(folder / "runs.csv", "run_id,p,objective\n1,2,3.4\n")
    assert (folder / "runs.csv").read_text().startswith("run_id")


@pytest.mark.parametrize("where", ["--json", "fit.png in --out"])
def test_a_pipe_as_an_output_is_refused_and_left_a_pipe(inputs, tmp_path, capsys, where):
    """Renaming a result over a named pipe (or a device: /dev/null as --json) would remove it: refused before any
    work, the pipe left as it was, nothing written."""
    pipe = tmp_path / ("o" if where != "--json" else "") / ("fit.png" if where != "--json" else "r.json")
    pipe.parent.mkdir(exist_ok=True)
    os.mkfifo(pipe)
    argv = [a.format(**{"in": inputs, "tmp": tmp_path}) for a in _fit()]
    if where == "--json":
        argv += ["--json", str(pipe)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{pipe}: not a regular file (a device or a pipe)" in err[0]
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode)
    assert not (tmp_path / "o" / "model.json").exists()


def test_a_symbolic_link_as_an_output_is_written_through_and_stays_a_link(inputs, tmp_path, capsys):
    target = tmp_path / "results" / "r.json"
    target.parent.mkdir()
    target.write_text("{}\n")
    link = tmp_path / "r.json"
    link.symlink_to(target)
    argv = [a.format(**{"in": inputs, "tmp": tmp_path}) for a in _fit("--json", str(link))]
    assert main(argv) == 0, capsys.readouterr().err
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert json.loads(target.read_text())["p"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o", "r.json", "results"]


@pytest.mark.parametrize(
    "name, content, what",
    [
        ("model.json", b"hand notes on the spindle\n", "not a JSON document"),
        ("model.json", b'{"format": "groupfit-ballscrew/1"}\n', "a model file (groupfit-ballscrew)"),
        ("fit.png", b"a photo of the set-up, not a PNG\n", "not a PNG image"),
    ],
    ids=["notes as model.json", "a ball-screw model as model.json", "notes as fit.png"],
)
def test_a_file_in_the_out_folder_is_replaced_only_when_it_is_an_earlier_output_of_its_kind(
    inputs, tmp_path, capsys, name, content, what
):
    """fit replaced every file of its output names in its --out folder, whatever it held."""
    folder = tmp_path / "o"
    folder.mkdir()
    (folder / name).write_bytes(content)
    before = _contents(inputs, tmp_path)
    status, err, _ = _run(_fit(), inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and what in err[0] and "--force" in err[0]
    assert _contents(inputs, tmp_path) == before
    assert _run((*_fit(), "--force"), inputs, tmp_path, capsys)[0] == 0
    assert json.loads((folder / "model.json").read_text())["format"].startswith("groupfit-model/")
    # its own outputs, and an AR(1) or global model of the same format, are replaced on every run
    assert _run(_fit(), inputs, tmp_path, capsys)[0] == 0
    assert (folder / "fit.png").read_bytes().startswith(b"\x89PNG")


def test_export_replaces_its_own_routines_but_not_a_hand_written_file_of_that_name(inputs, tmp_path, capsys):
    argv = ("export", "{in}/model.json", "--target", "c", "--out", "{tmp}/c")
    assert _run(argv, inputs, tmp_path, capsys)[0] == 0
    assert _run(argv, inputs, tmp_path, capsys)[0] == 0  # an earlier export is replaced
    own = tmp_path / "c" / "groupfit_model.c"
    own.write_text("int my_own_code(void) { return 42; }\n")
    before = _contents(inputs, tmp_path)
    status, err, _ = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and "a file groupfit did not write" in err[0]
    assert _contents(inputs, tmp_path) == before  # the header written before it is not left either
    assert _run((*argv, "--force"), inputs, tmp_path, capsys)[0] == 0
    assert "gf_step" in own.read_text()


def test_sweep_refuses_a_users_table_in_its_report_folder_before_it_runs_the_study(inputs, tmp_path, capsys):
    report = tmp_path / "report"
    report.mkdir()
    (report / "runs.csv").write_text("time_s,T1,error_um\n0,20.1,0.5\n")
    argv = ("sweep", "{in}/sweep.toml", "--workers", "1", "--db", "{tmp}/s.sqlite", "--out", "{tmp}/report")
    status, err, unchanged = _run(argv, inputs, tmp_path, capsys)
    assert status == 2 and len(err) == 1 and "a table that is not an earlier output" in err[0] and unchanged
    assert not (tmp_path / "s.sqlite").exists()  # refused before the study, whose database it would have written
