"""Reading and checking TOML configurations: one toolkit for run, sweep and scenario files.

:func:`read_toml` reads a file or says in one line why it cannot;
:class:`Table` gives typed access to one table, remembers which keys were
read and refuses the others in :meth:`Table.finish`. Every message names the
file (when known) and the key: ``file.toml: config key 'model.p': expected an
integer, got 'x'``, ``file.toml: unknown key 'pee' in [model]; known keys: …``.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any, Iterable

from groupfit.errors import InputError
from groupfit.io import read_input_text


def read_toml(path: str | Path, what: str = "configuration file") -> dict[str, Any]:
    """The parsed file; InputError when it is missing, not UTF-8 or not valid TOML."""
    path = Path(path)
    try:
        return tomllib.loads(read_input_text(path, what))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not valid TOML ({exc})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None


def check_tables(raw: dict[str, Any], tables: Iterable[str], label: str | None = None) -> None:
    """Refuse a top-level table this kind of file does not have, or a key that is not a table."""
    tables = tuple(tables)
    prefix = f"{label}: " if label else ""
    if isinstance(raw.get("kind"), str) and "kind" not in tables:
        raise InputError(
            f"{prefix}kind = {raw['kind']!r} at the top level: a scenario configuration for groupfit simulate, not "
            f"this kind of file, whose tables are {', '.join(tables)}"
        )
    for table, values in raw.items():
        if table not in tables and not isinstance(values, dict):
            raise InputError(
                f"{prefix}key '{table}' at the top level: every key belongs in a table (e.g. [{tables[0]}]); "
                f"the tables are {', '.join(tables)}"
            )
        if table not in tables:
            raise InputError(f"{prefix}unknown table [{table}]; the tables are {', '.join(tables)}")
        if not isinstance(values, dict):
            raise InputError(f"{prefix}'{table}' must be a table ([{table}])")


class Table:
    """Typed access to one configuration table that remembers which keys were read.

    Parameters
    ----------
    data : dict
        The table's values.
    name : str
        Its dotted name (``""`` for the top level).
    label : str, optional
        The file, named at the start of every message.
    """

    def __init__(self, data, name: str, label: str | None = None):
        self.name, self.label, self.used = name, label, set()
        if not isinstance(data, dict):
            raise self.fail_key(name, "must be a table ([section])")
        self.data = data

    def key(self, key: str) -> str:
        return f"{self.name}.{key}" if self.name else key

    def fail_key(self, dotted: str, what: str) -> InputError:
        """The error for a key given by its full dotted name."""
        prefix = f"{self.label}: " if self.label else ""
        return InputError(f"{prefix}config key '{dotted}': {what}")

    def fail(self, key: str, what: str) -> InputError:
        """The error for a key of this table."""
        return self.fail_key(self.key(key), what)

    def __contains__(self, key: str) -> bool:
        return key in self.data

    def get(self, key, default=None):
        self.used.add(key)
        return self.data.get(key, default)

    def number(self, key, default=None, *, positive=False, nonnegative=False) -> float:
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(key, f"expected a number, got {value!r}")
        if positive and value <= 0:
            raise self.fail(key, f"must be positive, got {value!r}")
        if nonnegative and value < 0:
            raise self.fail(key, f"must not be negative, got {value!r}")
        return float(value)

    def integer(self, key, default=None, *, minimum: int | None = 1) -> int:
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"expected an integer, got {value!r}")
        if minimum is not None and value < minimum:
            raise self.fail(key, f"must be at least {minimum}, got {value}")
        return int(value)

    def string(self, key, default=None, choices=None) -> str:
        value = self.get(key, default)
        if not isinstance(value, str):
            raise self.fail(key, f"expected a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.fail(key, f"must be one of {', '.join(choices)}, got {value!r}")
        return value

    def strings(self, key, default=None) -> list[str]:
        value = self.get(key, default)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.fail(key, f"expected a list of strings, got {value!r}")
        return list(value)

    def boolean(self, key, default=None) -> bool:
        value = self.get(key, default)
        if not isinstance(value, bool):
            raise self.fail(key, f"expected true or false, got {value!r}")
        return value

    def vector(self, key, default, length) -> tuple[float, ...]:
        value = self.get(key, default)
        if (
            not isinstance(value, (list, tuple))
            or len(value) != length
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)
        ):
            raise self.fail(key, f"expected a list of {length} numbers, got {value!r}")
        return tuple(float(v) for v in value)

    def sub(self, key) -> "Table":
        return type(self)(self.get(key, {}), self.key(key), self.label)

    def finish(self, hint: str | None = None) -> None:
        """Refuse every key that was not read: a misspelt key is an error, never silently ignored."""
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            prefix = f"{self.label}: " if self.label else ""
            where = f" in [{self.name}] (config key '{self.key(unknown[0])}')" if self.name else ""
            known = ", ".join(sorted(self.used)) or "none"
            raise InputError(f"{prefix}unknown key '{unknown[0]}'{where}; {hint or f'known keys: {known}'}")
