"""The Python rule's decisions on a stream, and the check that another build makes the same ones."""

import numpy as np

from groupfit.runtime import SwitchingRule


def python_replay(model, temps, precision="double"):
    """Each sample of ``temps`` through :class:`SwitchingRule`: codes, groups, faults, switches and outputs."""
    rule = SwitchingRule(model, precision=precision)
    rule.reset()
    results = [rule.step(row) for row in temps]
    return {
        "code": np.array([r.code for r in results]),
        "group": np.array([r.group for r in results]),
        "fault": np.array([r.fault for r in results]),
        "switched": np.array([r.switched for r in results]),
        "prediction_um": np.array([r.prediction_um for r in results]),
        "compensation_um": np.array([r.compensation_um for r in results]),
    }


def assert_same_decisions(c_out, py, tolerance=None):
    """A C driver's outputs against :func:`python_replay`: the same decisions, the outputs bit for bit or within
    ``tolerance``."""
    assert np.array_equal(c_out.code, py["code"])
    assert np.array_equal(c_out.group, py["group"])
    assert np.array_equal(c_out.fault, py["fault"])
    assert np.array_equal(c_out.switched, py["switched"])
    if tolerance is None:  # bit for bit
        assert c_out.prediction_um.tobytes() == py["prediction_um"].tobytes()
        assert c_out.compensation_um.tobytes() == py["compensation_um"].tobytes()
    else:
        assert np.max(np.abs(c_out.prediction_um - py["prediction_um"])) <= tolerance
        assert np.max(np.abs(c_out.compensation_um - py["compensation_um"])) <= tolerance
