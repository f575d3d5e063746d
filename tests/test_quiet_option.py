"""Every verb a script runs over its runs takes ``--quiet``, so one option list serves them all."""

import pytest

from groupfit.cli import main


@pytest.mark.parametrize("verb", ["fit", "compare", "diagnose", "replay", "export", "simulate", "sweep"])
def test_every_verb_takes_quiet(verb, capsys):
    with pytest.raises(SystemExit) as exit_code:
        main([verb, "--help"])
    assert exit_code.value.code == 0
    assert "--quiet" in capsys.readouterr().out
