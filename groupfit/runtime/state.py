"""The run-time rule's state after a run: kept in the model file, so that the rest of the recording is replayed as
the controller, which ran through, would meet it, even where the modelling file is no longer at hand.

The state is every attribute a sample changes: the switching rule's (the
sample count, the group, the held readings, the derived inputs' memories and
delay lines, the bumpless transfer, the rate limiter's last output, the
reference readings) and its recalibration filter's (states, covariance,
correction, clamps). Configuration, which the model file itself gives, is
not part of it. :func:`capture` turns it into plain JSON values (a float in
double precision is kept exactly); :func:`restore` puts it back into a rule
built from the same model, and refuses a state that does not fit it.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping

from groupfit.errors import InputError

RULE_KEY = "rule"
RECALIBRATION_KEY = "recalibration"
CONFIGURATION = frozenset({"tables", "precision", "recal", "table"})
"""Public attributes of the rule and its filter that the model file sets, not the samples."""


def _plain(value: Any) -> Any:
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, int):  # a bool too
        return value
    return float(value)


def _attributes(holder: Any) -> dict[str, Any]:
    names = [name for name in vars(holder) if not name.startswith("_") and name not in CONFIGURATION]
    return {name: getattr(holder, name) for name in names}


def capture(rule: Any) -> dict[str, dict[str, Any]]:
    """The state of a :class:`~groupfit.runtime.SwitchingRule` (and its filter) as JSON values."""
    return {
        RULE_KEY: {name: _plain(value) for name, value in _attributes(rule).items()},
        RECALIBRATION_KEY: {name: _plain(value) for name, value in _attributes(rule.recal).items()},
    }


def _converted(now: Any, saved: Any, real: Callable[[Any], Any], where: str) -> Any:
    """``saved`` in the type of the attribute's value ``now`` (floats in the rule's precision)."""
    if isinstance(now, (list, tuple)):
        if not isinstance(saved, (list, tuple)) or len(saved) != len(now):
            raise InputError(f"{where} must be a list of {len(now)}")
        return [_converted(a, b, real, f"{where}[{k}]") for k, (a, b) in enumerate(zip(now, saved))]
    if isinstance(now, bool):
        if not isinstance(saved, bool):
            raise InputError(f"{where} must be true or false")
        return saved
    if isinstance(now, int):
        if isinstance(saved, bool) or not isinstance(saved, int):
            raise InputError(f"{where} must be a whole number")
        return saved
    if isinstance(saved, bool) or not isinstance(saved, (int, float)):
        raise InputError(f"{where} must be a number")
    return real(float(saved))


def restore(rule: Any, state: Mapping[str, Any], where: str = "end_state") -> None:
    """Put a :func:`capture`\\ d state back into ``rule`` (built from the same model file); a state that does not
    fit the rule (another model's, a key missing or unknown, a list of another length) is refused."""
    if not isinstance(state, Mapping):
        raise InputError(f"{where} must be an object with '{RULE_KEY}' and '{RECALIBRATION_KEY}'")
    for key, holder in ((RULE_KEY, rule), (RECALIBRATION_KEY, rule.recal)):
        saved = state.get(key)
        now = _attributes(holder)
        if not isinstance(saved, Mapping) or set(saved) != set(now):
            raise InputError(f"{where}.{key} does not hold the state of this model's rule: {', '.join(sorted(now))}")
        values = {name: _converted(now[name], saved[name], rule._real, f"{where}.{key}.{name}") for name in now}
        for name, value in values.items():
            setattr(holder, name, value)


__all__ = ["RECALIBRATION_KEY", "RULE_KEY", "capture", "restore"]
