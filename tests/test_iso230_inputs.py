"""``groupfit iso230`` on bad runs: one line naming the file, row, column or value, exit 2, nothing written.

And the inputs it takes with a defined result: every spelling of a direction it reads, deviations up to the
plausible limit every verb puts on an error (``ERROR_LIMIT_UM``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.data import ERROR_LIMIT_UM
from groupfit.errors import InputError
from groupfit.iso230 import TARGET_LIMIT_MM, evaluate, load_runs

Change = Callable[[pd.DataFrame], pd.DataFrame]


def three_target_runs() -> pd.DataFrame:
    """Three targets, two runs each way, in the cycle's order; index i is data row i + 1 of the CSV."""
    rows = []
    for run in (1, 2):
        rows += [("+", target, 1.0 + run + target / 10) for target in (0.0, 10.0, 20.0)]
        rows += [("-", target, -1.0 - run + target / 10) for target in (20.0, 10.0, 0.0)]
    return pd.DataFrame(rows, columns=["direction", "target_mm", "deviation_um"])


def with_cell(column: str, index: int, value) -> Change:
    """A change of ``three_target_runs`` that writes ``value`` into one cell."""

    def change(frame: pd.DataFrame) -> pd.DataFrame:
        frame[column] = frame[column].astype(object)
        frame.loc[index, column] = value
        return frame

    return change


def every_deviation(value: float) -> Change:
    return lambda frame: frame.assign(deviation_um=value)


def integer_directions_with(index: int, value: int) -> Change:
    """Directions written as 1/-1 (read as integers), one of them ``value``."""

    def change(frame: pd.DataFrame) -> pd.DataFrame:
        signs = np.where(frame.direction == "+", 1, -1)
        signs[index] = value
        return frame.assign(direction=signs)

    return change


def run_verb(tmp_path, frame: pd.DataFrame, capsys) -> tuple[int, list[str]]:
    """Write ``frame`` to runs.csv, run ``groupfit iso230`` with --json and --out: the exit status, stderr's lines."""
    frame.to_csv(tmp_path / "runs.csv", index=False)
    out = ["--json", str(tmp_path / "r.json"), "--out", str(tmp_path / "figs")]
    code = main(["iso230", str(tmp_path / "runs.csv"), *out])
    return code, capsys.readouterr().err.strip().splitlines()


def assert_refused(tmp_path, code: int, err: list[str], *fragments: str) -> None:
    """Exit 2, one line naming runs.csv and every fragment, no option iso230 lacks, nothing written."""
    assert code == 2
    assert len(err) == 1, err
    line = err[0]
    assert "runs.csv" in line and all(fragment in line for fragment in fragments), line
    for foreign in ("--resample", "--data", "--temps", "--range-error", "np.", "Traceback"):
        assert foreign not in line
    assert not (tmp_path / "r.json").exists()
    assert not (tmp_path / "figs" / "iso230.png").exists()


@pytest.mark.parametrize(
    "change, fragments",
    [
        pytest.param(
            with_cell("deviation_um", 2, 1e200),
            ("row 3, column 'deviation_um': 1e+200 µm", f"beyond the plausible ±{ERROR_LIMIT_UM:g} µm", "unit"),
            id="deviation 1e200",
        ),
        pytest.param(with_cell("deviation_um", 4, 1e20), ("row 5, column 'deviation_um': 1e+20 µm",), id="1e20"),
        pytest.param(
            with_cell("deviation_um", 0, -ERROR_LIMIT_UM * 1.001),
            (f"row 1, column 'deviation_um': {-ERROR_LIMIT_UM * 1.001:g} µm",),
            id="just beyond the limit",
        ),
        pytest.param(every_deviation(1e308), ("row 1, column 'deviation_um': 1e+308 µm", "(12 such"), id="all 1e308"),
        pytest.param(with_cell("deviation_um", 3, None), ("row 4, column 'deviation_um' is empty",), id="no deviation"),
        pytest.param(
            with_cell("deviation_um", 3, "---"), ("row 4, '-,20.0,---': text where a number belongs",), id="marked"
        ),
        pytest.param(with_cell("deviation_um", 3, "abc"), ("row 4, '-,20.0,abc'", "header"), id="word deviation"),
        pytest.param(with_cell("target_mm", 1, "x"), ("row 2, '+,x,3.0'", "header"), id="word target"),
        pytest.param(with_cell("target_mm", 1, None), ("row 2, column 'target_mm' is empty",), id="no target"),
        pytest.param(with_cell("target_mm", 1, "nan"), ("row 2, column 'target_mm' is empty",), id="target nan"),
        pytest.param(
            with_cell("target_mm", 1, "inf"), ("row 2, column 'target_mm': 'inf' is not a finite number",), id="inf"
        ),
        pytest.param(
            lambda f: f.assign(target_mm=f.target_mm.where(f.target_mm != 20.0, 1e300)),
            ("row 3, column 'target_mm': 1e+300 mm", f"±{TARGET_LIMIT_MM:g} mm", "unit"),
            id="target 1e300",
        ),
        pytest.param(
            integer_directions_with(3, 0), ("row 4, column 'direction': '0' is no direction",), id="direction 0"
        ),
        pytest.param(
            integer_directions_with(5, 2), ("row 6, column 'direction': '2' is no direction",), id="direction 2"
        ),
        pytest.param(with_cell("direction", 3, None), ("row 4, column 'direction' is empty",), id="no direction"),
        pytest.param(with_cell("direction", 3, "cw"), ("row 4, column 'direction': 'cw' is no direction",), id="cw"),
        pytest.param(
            lambda f: f[f.target_mm == 10.0],
            ("column 'target_mm' holds one target position only (10 mm)",),
            id="single target",
        ),
        pytest.param(
            lambda f: f.iloc[:6], ("1 run(s) per direction", "at least twice from each side"), id="single run"
        ),
    ],
)
def test_bad_runs_are_refused_with_one_line_and_nothing_written(tmp_path, capsys, change, fragments):
    code, err = run_verb(tmp_path, change(three_target_runs()), capsys)
    assert_refused(tmp_path, code, err, *fragments)


def test_a_direction_and_a_deviation_in_one_row_are_named_by_the_same_row_number(tmp_path, capsys):
    rows = []
    for column, value in (("direction", "sideways"), ("deviation_um", None)):
        code, err = run_verb(tmp_path, with_cell(column, 3, value)(three_target_runs()), capsys)
        assert_refused(tmp_path, code, err, f"row 4, column '{column}'")
        rows.append(err[0].split(": row ")[1].split(",")[0])
    assert rows == ["4", "4"]


@pytest.mark.parametrize(
    "path, message",
    [("missing.csv", "data file not found; check its path"), (".", "is a folder; give a data file")],
    ids=["missing file", "folder"],
)
def test_a_run_that_is_no_file_is_refused_without_naming_an_option_iso230_lacks(tmp_path, capsys, path, message):
    code = main(["iso230", str(tmp_path / path), "--json", str(tmp_path / "r.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0] and "--" not in err[0]
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize(
    "up, down",
    [("+", "-"), ("UP", "Down"), ("↑", "↓"), ("1.0", "-1.0"), ("positive", "negative"), ("forward", "backward")],
)
def test_every_spelling_of_a_direction_gives_the_same_evaluation(up, down):
    frame = three_target_runs()
    spelled = frame.assign(direction=frame.direction.map({"+": f" {up} ", "-": down}))
    assert load_runs(spelled).axis() == load_runs(frame).axis()


def test_deviations_at_the_limit_are_evaluated_and_written_as_finite_json(tmp_path, capsys):
    frame = three_target_runs()
    frame["deviation_um"] = np.where(np.arange(len(frame)) % 2, ERROR_LIMIT_UM, -ERROR_LIMIT_UM)
    code, err = run_verb(tmp_path, frame, capsys)
    assert code == 0 and err == []
    result = json.loads((tmp_path / "r.json").read_text())
    assert all(math.isfinite(value) for value in result["axis_um"].values())
    assert (tmp_path / "figs" / "iso230.png").stat().st_size > 0


@pytest.mark.parametrize(
    "up, targets, message",
    [
        ([[1.0, np.inf], [2.0, 3.0]], [0.0, 10.0], "run 1 ↑ at 10 mm: deviation inf µm"),
        ([[1.0, 2.0], [2.0, 1e200]], [0.0, 10.0], "run 2 ↑ at 10 mm: deviation 1e+200 µm"),
        ([[1.0, 2.0], [2.0, 3.0]], [0.0, np.nan], "target position nan mm"),
        ([[1.0, 2.0], [2.0, 3.0]], [0.0, 1e300], "target position 1e+300 mm"),
    ],
)
def test_evaluate_refuses_what_no_axis_measures(up, targets, message):
    with pytest.raises(InputError, match=message.replace("+", r"\+")):
        evaluate(np.array(up), np.zeros((2, 2)), targets)


@pytest.mark.parametrize(
    "target, deviation, to_mm, to_um, named",
    [
        ("target_um", "deviation_nm", 1000.0, 1000.0, {"target_um": "um", "deviation_nm": "nm"}),
        ("P [mm]", "dev (mm)", 1.0, 1e-3, {"dev (mm)": "mm"}),
        ("pos", "dx", 1.0, 1.0, {}),
        ("P [0.1 mm]", "dev [0.1 µm]", 10.0, 10.0, {"P [0.1 mm]": "0.1 mm", "dev [0.1 µm]": "0.1 µm"}),
        ("pos", "dev [µm/10]", 1.0, 10.0, {"dev [µm/10]": "µm/10"}),
        ("pos", "dev [10 nm]", 1.0, 100.0, {"dev [10 nm]": "10 nm"}),
    ],
)
def test_a_unit_in_the_column_name_is_read_as_that_unit(tmp_path, capsys, target, deviation, to_mm, to_um, named):
    """The same runs logged in other units (named in the columns) give the same evaluation; the report and the
    JSON say which column was read in a unit other than the one it is given in."""
    frame = three_target_runs()
    logged = pd.DataFrame(
        {"direction": frame.direction, target: frame.target_mm * to_mm, deviation: frame.deviation_um * to_um}
    )
    logged.to_csv(tmp_path / "logged.csv", index=False)
    args = ["iso230", str(tmp_path / "logged.csv"), "--target", target, "--deviation", deviation]
    assert main([*args, "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["axis_um"] == pytest.approx(load_runs(frame).axis(), rel=1e-12)
    assert [p["target_mm"] for p in result["positions"]] == pytest.approx([0.0, 10.0, 20.0])
    assert {c: r["unit"] for c, r in result.get("columns_read_in", {}).items()} == named
    assert main(args) == 0
    report = capsys.readouterr().out
    assert all(f"column   '{c}' read in {u} (by its name)" in report for c, u in named.items())


@pytest.mark.parametrize(
    "same", [("--target", "--deviation"), ("--direction", "--deviation"), ("--target", "--direction")]
)
def test_one_column_named_for_two_roles_is_refused(tmp_path, capsys, same):
    frame = three_target_runs().rename(columns={"target_mm": "P"})
    frame.to_csv(tmp_path / "runs.csv", index=False)
    args = ["iso230", str(tmp_path / "runs.csv"), "--target", "P", *(option for role in same for option in (role, "P"))]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "column 'P' given as both" in err[0] and "runs.csv" in err[0]
