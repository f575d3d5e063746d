"""Run configurations: TOML files merged with command-line options.

A configuration has up to four tables; every key is optional::

    [data]
    path = "../datasets/synthetic_cycle.csv"   # relative to the config file
    time = "time_s"
    temps = ["T1", "T2", "T3", "T4"]
    error = "error_um"
    validate = ["../datasets/other_run.csv"]
    temp_range = [-50, 500]    # plausible temperatures (°C); a reading outside is refused
    error_limit = 1e5          # largest plausible |error| (µm)
    period_tolerance = 2       # % of the period an interval may deviate by (a jittering clock)
    resample_s = 60            # average the readings of every 60 s (a gap splits the log)
    ambient = "T15"            # the ambient sensor, whatever its name
    keep_glitches = false      # true: keep error and temperature readings that leave their neighbours and come back
    encoding = "cp1250"        # the text's encoding (default: told from the bytes)

    [model]
    p = "auto"                 # or a whole number; "auto": choose p by p_rule over 0…pmax
    pmax = 3
    p_rule = "next-run"        # the expected next-run error (one-SE rule); "bic" (in sample); or "target":
                               # fewest breaks with R <= p_target
    p_target = "20%"           # µm, or a percentage of R at p = 0
    n = 3
    c = 3.0
    objective = "sae"          # or "sse"
    intercept = true
    criterion = "T1"           # switching criterion sensor (default: the most active)

    [search]
    method = "ga"              # or "exact"
    seed = 0
    population_size = 60
    max_generations = 300
    stall_generations = 30
    polish = true
    certify = "auto"           # GA: also run the exact search and report the gap; true, false
                               # or "auto" (when cheap: N²/2 ≤ 5 M segments for sse, 0.2 M for sae)

    [output]
    dir = "groupfit-out"       # relative to the folder the command runs in (not the config file's): outputs
                               # land where the user works, whichever configuration wrote them

    [compare]                  # groupfit compare
    pmax = 4
    heat = "speed_rpm"         # AR(1) heat-level column
    ar1_scaling = "heat_law"   # or "rise": C2 of unseen levels by early temperature rise
    ar1_start = "measured"     # or "zero": each free run starts from 0 (the paper's ΔL(0) = 0)
    ar1_fit = "one_step"       # or "free_run": C1, C2 (and the structural gain) on the free-run error
    heat_exponent = 1.6667     # heat law C2 ∝ level^exponent (default 5/3 exactly)
    rise_sensor = "T2"         # with ar1_scaling = "rise"
    rise_window_s = 6000.0
    structural_sensor = "T5"   # optional structural term g·ΔT (g in µm/K)
    structural_gain_um_per_K = 3.18
    conditions = ["speed_rpm"] # columns whose changes are changes of operating condition
    p_target = "20%"           # target rule: µm or a percentage of R at p = 0

Command-line options override the file. The defaults are those of
:class:`groupfit.settings.RunSettings`. Unknown tables or keys, and values of
the wrong type, are errors that name the key.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable

from groupfit.ar1.modelfile import MAX_HEAT_EXPONENT
from groupfit.data_options import MAX_PERIOD_TOLERANCE, encoding_name, parse_period_tolerance
from groupfit.errors import InputError
from groupfit.grouping import MAX_SPACING
from groupfit.objective import OBJECTIVES
from groupfit.search.base import METHODS
from groupfit.settings import AR1_FIT_METHODS, AR1_SCALINGS, AR1_STARTS, P_RULES, RunSettings
from groupfit.tomlconfig import Table, check_tables, read_toml


def _seed(table: Table, key: str) -> int:
    return table.integer(key, minimum=0)


def _at_least(minimum: int) -> Callable[[Table, str], int]:
    """A whole number of at least ``minimum`` (a population of 2 or more, one generation or more)."""
    return lambda table, key: table.integer(key, minimum=minimum)


def _columns(table: Table, key: str) -> list[str]:
    names = table.strings(key)
    if not names:
        raise table.fail(key, "expected one or more column names; leave the key out to take the T1, T2 … columns")
    return names


def _positive(table: Table, key: str) -> float:
    return table.number(key, positive=True)


def _heat_exponent(table: Table, key: str) -> float:
    """The heat law's exponent, in (0, 4] as a deployable AR(1) model holds it."""
    value = table.number(key, positive=True)
    if value > MAX_HEAT_EXPONENT:
        raise table.fail(key, f"expected a number in (0, {MAX_HEAT_EXPONENT:g}], got {value!r}")
    return value


def _number(table: Table, key: str) -> int | float:
    table.number(key)
    return table.data[key]


def _period_tolerance(table: Table, key: str) -> int | float:
    value = _number(table, key)
    parsed_period_tolerance(table, key)
    return value


def parsed_period_tolerance(table: Table, key: str) -> float | None:
    """The tolerance ``key`` gives (a percentage: 2, or "5%"), as a fraction of the period; refused naming the
    key."""
    value = table.get(key)
    try:
        return parse_period_tolerance(value)
    except InputError:
        limit = f"{100 * MAX_PERIOD_TOLERANCE:g}"
        raise table.fail(key, f"must be a percentage of the period, 0 up to but not {limit}, got {value!r}") from None


def _path(table: Table, key: str) -> str:
    value = table.string(key)
    if not value.strip():
        raise table.fail(key, "an empty path; name the run's file (relative to the configuration's folder)")
    return value


def _paths(table: Table, key: str) -> list[str]:
    values = table.strings(key)
    if any(not value.strip() for value in values):
        raise table.fail(key, "an empty path among them; name each run's file (relative to the configuration's folder)")
    return values


def _encoding(table: Table, key: str) -> str:
    value = table.string(key)
    try:
        return encoding_name(value)
    except InputError:
        raise table.fail(key, f"expected a text encoding (cp1250, utf-8 …), got {value!r}") from None


def _whole_or_auto(table: Table, key: str) -> int | str:
    value = table.get(key)
    if value != "auto" and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
        raise table.fail(key, f'expected a whole number ≥ 0 or "auto", got {value!r}')
    return value


def _spacing(table: Table, key: str) -> float:
    value = table.number(key, nonnegative=True)
    if value > MAX_SPACING:
        raise table.fail(key, f"the spacing coefficient must be a number from 0 to {MAX_SPACING:g}, got {value!r}")
    return table.data[key]


STRUCTURAL_GAIN_LIMIT = 1e4
"""The largest structural gain α·L taken, µm per K (steel over 5 m: about 60)."""


def _structural_gain(table: Table, key: str) -> float:
    value = table.number(key)
    if abs(value) > STRUCTURAL_GAIN_LIMIT:
        raise table.fail(key, f"expected α·L in µm per K, at most {STRUCTURAL_GAIN_LIMIT:g} in size, got {value!r}")
    return value


def _check_compare_keys(compare: dict[str, Any], label: str) -> None:
    """Refuse ``[compare]`` keys that would have no effect with the others given."""
    fail = Table(compare, "compare", label).fail
    if "structural_gain_um_per_K" in compare and "structural_sensor" not in compare:
        raise fail("structural_gain_um_per_K", "has no effect without structural_sensor (the sensor it multiplies)")
    if compare.get("ar1_scaling", "heat_law") != "rise":
        for key in ("rise_sensor", "rise_window_s"):
            if key in compare:
                raise fail(key, 'applies with ar1_scaling = "rise" only (unseen levels scaled by the early rise)')


def _certify(table: Table, key: str) -> bool | str:
    value = table.get(key)
    if value != "auto" and not isinstance(value, bool):
        raise table.fail(key, f'expected true, false or "auto", got {value!r}')
    return value


def parsed_temp_range(table: Table, key: str) -> tuple[float, float]:
    """A ``[LOW, HIGH]`` range of plausible temperatures (°C) under ``key``, refused naming the key."""
    value = table.get(key)
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
        or not value[0] < value[1]
    ):
        raise table.fail(key, f"expected [LOW, HIGH] in °C with LOW < HIGH, got {value!r}")
    return float(value[0]), float(value[1])


def _target(table: Table, key: str) -> str | int | float:
    value = table.get(key)
    if not isinstance(value, str):
        table.number(key)
    return value


SCHEMA: dict[str, dict[str, Callable[[Table, str], Any]]] = {
    "data": {
        "path": _path,
        "time": Table.string,
        "temps": _columns,
        "error": Table.string,
        "validate": _paths,
        "temp_range": parsed_temp_range,
        "error_limit": lambda table, key: table.number(key, positive=True),
        "period_tolerance": _period_tolerance,
        "resample_s": lambda table, key: table.number(key, positive=True),
        "ambient": Table.string,
        "keep_glitches": Table.boolean,
        "encoding": _encoding,
    },
    "model": {
        "p": _whole_or_auto,
        "pmax": _at_least(0),
        "p_rule": lambda table, key: table.string(key, choices=P_RULES),
        "p_target": _target,
        "n": _at_least(0),
        "c": _spacing,
        "objective": lambda table, key: table.string(key, choices=OBJECTIVES),
        "intercept": Table.boolean,
        "criterion": Table.string,
        "reference": Table.string,
    },
    "search": {
        "method": lambda table, key: table.string(key, choices=METHODS),
        "seed": _seed,
        "population_size": _at_least(2),
        "max_generations": _at_least(1),
        "stall_generations": _at_least(1),
        "polish": Table.boolean,
        "certify": _certify,
    },
    "output": {"dir": Table.string},
    "compare": {
        "pmax": _at_least(0),
        "heat": Table.string,
        "ar1_scaling": lambda table, key: table.string(key, choices=AR1_SCALINGS),
        "ar1_start": lambda table, key: table.string(key, choices=AR1_STARTS),
        "ar1_fit": lambda table, key: table.string(key, choices=AR1_FIT_METHODS),
        "heat_exponent": _heat_exponent,
        "rise_sensor": Table.string,
        "rise_window_s": _positive,
        "structural_sensor": Table.string,
        "structural_gain_um_per_K": _structural_gain,
        "conditions": Table.strings,
        "p_target": _target,
    },
}
"""Every table and key of a run configuration, with the reader that checks its value."""

PATH_KEYS = {("data", "path"), ("data", "validate")}


PACKAGED_DEFAULT = Path(__file__).resolve().parent / "_data" / "configs" / "default.toml"
"""The default configuration as installed with the package, next to the data sets it names."""


def default_config_path() -> Path | None:
    """``configs/default.toml`` in the working folder, else in the source tree, else the packaged copy.

    The packaged copy (``groupfit/_data/``: the default configuration and the
    data sets it names) makes ``groupfit fit`` and ``groupfit compare`` work
    from any folder after a plain ``pip install``; in a source checkout it
    links to ``configs/`` and ``datasets/``.
    """
    for candidate in (
        Path.cwd() / "configs" / "default.toml",
        Path(__file__).resolve().parents[1] / "configs" / "default.toml",
        PACKAGED_DEFAULT,
    ):
        if candidate.is_file():
            return candidate
    return None


def read_config(path: str | Path | None) -> RunSettings:
    """Read and check a TOML configuration; relative data paths are resolved against its folder.

    ``None``: the defaults (:class:`groupfit.settings.RunSettings`).
    """
    if path is None:
        return RunSettings()
    path = Path(path)
    raw = read_toml(path, "configuration file")
    base = path.resolve().parent
    tables = check_config(raw, str(path))
    for table, key in PATH_KEYS:
        value = tables.get(table, {}).get(key)
        if value is not None:
            tables[table][key] = (
                [str((base / v).resolve()) for v in value] if isinstance(value, list) else str((base / value).resolve())
            )
    return RunSettings.from_tables(tables)


def check_config(raw: dict, label: str) -> dict[str, dict[str, Any]]:
    """The checked tables; InputError naming the first unknown table or key, or wrongly typed value."""
    check_tables(raw, SCHEMA, label)
    checked = {}
    for name, values in raw.items():
        table = Table(values, name, label)
        checked[name] = {key: read(table, key) for key, read in SCHEMA[name].items() if key in table}
        table.finish(f"known keys: {', '.join(SCHEMA[name])}")
    _check_compare_keys(checked.get("compare", {}), label)
    return checked
