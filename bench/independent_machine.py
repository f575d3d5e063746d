"""The independent lumped RC machine, as the benches import it; the simulator lives in ``tests/support``.

``from independent_machine import scenarios`` (with ``bench/`` on the path, as every bench script has) keeps
working: this module puts ``tests/`` on the path and stands aside for ``support.independent_machine``, so the
tests and the benches share one module (the same ``Scenario`` class, the same functions).
"""

import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))

from support import independent_machine  # noqa: E402

sys.modules[__name__] = independent_machine
