"""Output files (mode, all-or-nothing, wrote lines), progress when stderr is not a terminal, cost estimates,
and the defaults a run given on the command line no longer inherits."""

from __future__ import annotations

import io
import json
import os
import re
import stat

import numpy as np
import pandas as pd
import pytest
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.cli import main
from groupfit.commands.common import StageProgress
from groupfit.errors import InputError
from groupfit.io import atomic_write_files, atomic_write_text, check_output_dir, check_output_file
from groupfit.model import ModelFile
from groupfit.search.exact import estimate_exact_cost
from groupfit.search.progress import ga_reporter


@pytest.fixture()
def umask_022():
    previous = os.umask(0o022)
    yield
    os.umask(previous)


def mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_files_get_the_umask_mode_not_0600(tmp_path, umask_022):
    atomic_write_text(tmp_path / "a.txt", "x")
    assert mode(tmp_path / "a.txt") == 0o644
    os.umask(0o077)
    atomic_write_text(tmp_path / "b.txt", "x")
    assert mode(tmp_path / "b.txt") == 0o600


def test_model_export_and_json_files_are_readable_by_others(tmp_path, umask_022, capsys):
    model, _ = synthetic_model()
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model))
    assert main(["replay", str(path), "--data", str(SYNTHETIC), "--json", str(tmp_path / "r.json")]) == 0
    assert main(["export", str(path), "--target", "all", "--out", str(tmp_path / "ex")]) == 0
    files = [tmp_path / "r.json", *sorted((tmp_path / "ex").iterdir())]
    assert len(files) == 7 and all(mode(f) == 0o644 for f in files)
    assert not list(tmp_path.rglob(".*.tmp*"))


def test_a_set_of_files_is_written_all_or_none(tmp_path):
    (tmp_path / "blocker").write_text("a file where a folder should be")
    with pytest.raises(InputError, match="cannot write"):
        atomic_write_files({tmp_path / "first.txt": "1", tmp_path / "blocker" / "second.txt": "2"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]


def test_output_checks_create_nothing(tmp_path):
    assert check_output_dir(tmp_path / "new" / "deeper") == tmp_path / "new" / "deeper"
    assert check_output_file(tmp_path / "other" / "r.json", "--json") == tmp_path / "other" / "r.json"
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match="not a folder"):
        check_output_dir(tmp_path / "file" / "x")
    with pytest.raises(InputError, match="needs a file name"):
        check_output_file(tmp_path, "--json")


def test_fit_wrote_line_names_the_json_file(tmp_path, capsys):
    out, result = tmp_path / "out", tmp_path / "json" / "fit.json"
    argv = ["fit", "--data", str(SYNTHETIC), "--temps", "T1,T2", "--p", "1", "--search", "exact", "--quiet"]
    assert main([*argv, "--out", str(out), "--json", str(result)]) == 0
    wrote = [line for line in capsys.readouterr().out.splitlines() if line.startswith("wrote")]
    assert wrote and str(result) in wrote[0] and str(out / "model.json") in wrote[0]
    assert json.loads(result.read_text())["breaks"]


def test_progress_is_logged_when_stderr_is_not_a_terminal(monkeypatch):
    clock = {"now": 0.0}
    monkeypatch.setattr("groupfit.commands.common.time.monotonic", lambda: clock["now"])
    stream = io.StringIO()
    progress = StageProgress(enabled=True, stream=stream)
    for k in range(1, 101):
        clock["now"] = k * 0.5
        progress("ga", k / 100)
    lines = stream.getvalue().splitlines()
    assert lines and all(line.startswith("progress ga: ") for line in lines)
    assert 5 <= len(lines) <= 15 and lines[-1].startswith("progress ga: 100 %")
    quick = io.StringIO()
    clock["now"] = 100.0
    fast = StageProgress(enabled=True, stream=quick)
    for k in range(11):
        fast("exact", k / 10)  # done at once: nothing logged
    assert quick.getvalue() == ""


def test_ga_progress_moves_to_the_stagnation_stop_and_never_back():
    shown = []
    report = ga_reporter(lambda stage, fraction: shown.append(fraction), max_generations=300, stall_generations=30)
    for generation in range(1, 61):
        report(generation, 10.0 if generation < 30 else 5.0)  # improves at 30, stops stalled at 60
    assert shown == sorted(shown) and shown[-1] == pytest.approx(1.0)


def test_exact_cost_estimate_grows_as_the_objective_says():
    small, large = estimate_exact_cost(1000, 9, "sae", 3), estimate_exact_cost(20000, 9, "sae", 3)
    assert large.bytes > 4e9 and large.seconds > 3600 and small.seconds < 60
    assert estimate_exact_cost(20000, 9, "sse", 3).bytes < 1e9


def test_exact_search_over_the_budget_is_refused_before_it_starts(tmp_path, capsys):
    n = 6000  # an exact sae search with p = 3 on 8 inputs: about 20 min by the estimate, over the budget
    rng = np.random.default_rng(0)
    frame = pd.DataFrame({"time_s": np.arange(1, n + 1) * 10.0})
    for k in range(8):
        frame[f"T{k + 1}"] = 20 + np.cumsum(rng.normal(size=n)) * 0.01
    frame["error_um"] = np.cumsum(rng.normal(size=n)) * 0.1
    data = tmp_path / "big.csv"
    frame.to_csv(data, index=False)
    argv = ["fit", "--data", str(data), "--search", "exact", "--p", "3", "--out", str(tmp_path / "o"), "--quiet"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--objective sse" in err[0] and "--search ga" in err[0] and "--no-budget" in err[0]
    assert not (tmp_path / "o").exists()
    step, seconds = re.search(r"keep one row in (\d+) of the run \(--resample (\d+):", err[0]).groups()
    assert float(seconds) == int(step) * 10.0  # the sampling period times the step
    cost = estimate_exact_cost(n // int(step), 9, "sae", 3)
    assert cost.seconds <= 15 * 60 and cost.bytes <= 4e9  # the advice brings the search within the budget
    # p = 0 is one least-squares fit, not a search: no budget to refuse it on
    argv[argv.index("3")] = "0"
    assert main(argv) == 0
    assert json.loads((tmp_path / "o" / "model.json").read_text())["p"] == 0


def test_data_on_the_command_line_does_not_inherit_the_default_runs(tmp_path, capsys):
    frame = pd.read_csv(SYNTHETIC)
    frame["speed_rpm"] = 2000.0 * frame["spindle_on"]  # the AR(1) model's heat column
    data = tmp_path / "run.csv"
    frame.to_csv(data, index=False)
    argv = ["fit", "--data", str(data), "--p", "1", "--search", "exact", "--quiet", "--out", str(tmp_path / "o")]
    assert main(argv) == 0
    model = json.loads((tmp_path / "o" / "model.json").read_text())
    # the file's sensors (and any stage's low-passes of them), not the default config's T1, T2
    assert list(ModelFile.from_dict(model).measured_inputs) == ["T1", "T2", "T3", "T4"]
    capsys.readouterr()
    argv = ["compare", "--data", str(data), "--pmax", "1", "--quiet", "--out", str(tmp_path / "c")]
    assert main([*argv, "--json", str(tmp_path / "c.json")]) == 0
    assert json.loads((tmp_path / "c.json").read_text())["runs"] == ["run"]  # no paper validation runs


def test_p_auto_at_the_edge_of_its_range_says_so(tmp_path, capsys):
    # the error's law changes a third into the run: one break is expected to serve far better than none
    rng = np.random.default_rng(0)
    t = np.arange(400) * 60.0
    t1, t2 = 20 + 10 * (1 - np.exp(-t / 6000)), 20 + 2 * np.sin(t / 3000)
    law = np.where(np.arange(400) < 120, 3 * (t1 - 20), 30 - 4 * (t1 - 20) + 5 * (t2 - 20))
    data = tmp_path / "regime.csv"
    pd.DataFrame({"time_s": t, "T1": t1, "T2": t2, "error_um": law + rng.normal(0, 0.2, 400)}).to_csv(data)
    argv = ["fit", "--data", str(data), "--temps", "T1,T2", "--p", "auto", "--pmax", "1", "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "p = 1 is the largest p tried" in out and "--pmax" in out
