"""A bad ``--c`` or ``--n`` is refused as an option, whether p is given or chosen by the next-run estimate."""

from pathlib import Path

import pytest

from groupfit.cli import main

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


@pytest.mark.parametrize(
    "option, value, named",
    [
        ("--c", "-1", "spacing coefficient c = -1 must be a number from 0 to"),
        ("--c", "nan", "spacing coefficient c = nan must be"),
        ("--c", "inf", "spacing coefficient c = inf must be"),
        ("--n", "-1", "n = -1: the soft offset must be a whole number ≥ 0"),
    ],
)
@pytest.mark.parametrize("p", [[], ["--p", "1"]])
def test_a_bad_spacing_is_refused_naming_the_option_not_the_run(tmp_path, capsys, option, value, named, p):
    out = tmp_path / "out"
    code = main(["fit", "--data", str(DATASETS / "paper_cycle.csv"), *p, option, value, "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and not out.exists()
    assert named in err
    assert "paper_cycle.csv" not in err and "record a longer run" not in err
