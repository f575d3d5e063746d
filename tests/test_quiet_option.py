"""The help a user reads: every verb a script runs over its runs takes ``--quiet`` (one option list serves them
all), and the text is plain, without the markup of the docstrings it comes from."""

import pytest

from groupfit.cli import main


@pytest.mark.parametrize("verb", ["fit", "compare", "diagnose", "replay", "export", "simulate", "sweep"])
def test_every_verb_takes_quiet(verb, capsys):
    with pytest.raises(SystemExit) as exit_code:
        main([verb, "--help"])
    assert exit_code.value.code == 0
    assert "--quiet" in capsys.readouterr().out


def test_the_top_level_help_is_plain_text(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "The groupfit command line." in out and "``" not in out
