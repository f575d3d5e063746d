"""Run configurations: TOML files merged with command-line options.

A configuration has up to four tables; every key is optional::

    [data]
    path = "../datasets/synthetic_cycle.csv"   # relative to the config file
    time = "time_s"
    temps = ["T1", "T2", "T3", "T4"]
    error = "error_um"
    validate = ["../datasets/other_run.csv"]

    [model]
    p = 3                      # or "auto": choose p by p_rule over 0…pmax
    pmax = 6
    p_rule = "bic"             # or "target": fewest breaks with R <= p_target
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

    [output]
    dir = "groupfit-out"

    [compare]                  # groupfit compare
    pmax = 4
    heat = "speed_rpm"         # AR(1) heat-level column
    ar1_scaling = "heat_law"   # or "rise": C2 of unseen levels by early temperature rise
    heat_exponent = 1.6667     # heat law C2 ∝ level^exponent
    rise_sensor = "T2"         # with ar1_scaling = "rise"
    rise_window_s = 6000.0
    structural_sensor = "T5"   # optional structural term g·ΔT (g in µm/K)
    structural_gain_um_per_K = 3.18
    conditions = ["speed_rpm"] # columns whose changes are changes of operating condition
    p_target = "20%"           # target rule: µm or a percentage of R at p = 0

Command-line options override the file. Unknown tables or keys, and values of
the wrong type, are errors that name the key.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from groupfit.errors import InputError
from groupfit.search.base import GA_DEFAULTS

SCHEMA: dict[str, dict[str, tuple[type, ...]]] = {
    "data": {"path": (str,), "time": (str,), "temps": (list,), "error": (str,), "validate": (list,)},
    "model": {
        "p": (int, str),
        "pmax": (int,),
        "p_rule": (str,),
        "p_target": (str, int, float),
        "n": (int,),
        "c": (int, float),
        "objective": (str,),
        "intercept": (bool,),
        "criterion": (str,),
    },
    "search": {
        "method": (str,),
        "seed": (int,),
        "population_size": (int,),
        "max_generations": (int,),
        "stall_generations": (int,),
        "polish": (bool,),
    },
    "output": {"dir": (str,)},
    "compare": {
        "pmax": (int,),
        "heat": (str,),
        "ar1_scaling": (str,),
        "heat_exponent": (int, float),
        "rise_sensor": (str,),
        "rise_window_s": (int, float),
        "structural_sensor": (str,),
        "structural_gain_um_per_K": (int, float),
        "conditions": (list,),
        "p_target": (str, int, float),
    },
}

DEFAULTS: dict[str, dict[str, Any]] = {
    "data": {"time": "time_s", "error": "error_um", "validate": []},
    "model": {"p": 3, "pmax": 6, "p_rule": "bic", "n": 3, "c": 3.0, "objective": "sae", "intercept": True},
    "search": {
        "method": "ga",
        "seed": 0,
        "population_size": GA_DEFAULTS.population_size,
        "max_generations": GA_DEFAULTS.max_generations,
        "stall_generations": GA_DEFAULTS.stall_generations,
        "polish": GA_DEFAULTS.polish,
    },
    "output": {"dir": "groupfit-out"},
    "compare": {
        "pmax": 4,
        "heat": "speed_rpm",
        "ar1_scaling": "heat_law",
        "conditions": ["speed_rpm"],
        "p_target": "20%",
    },
}

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


def read_config(path: str | Path | None) -> dict[str, dict[str, Any]]:
    """Read and check a TOML configuration; relative data paths are resolved against its folder."""
    config = {table: dict(values) for table, values in DEFAULTS.items()}
    if path is None:
        return config
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: configuration file not found")
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not valid TOML ({exc})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file") from None
    check_config(raw, str(path))
    base = path.resolve().parent
    for table, values in raw.items():
        for key, value in values.items():
            if (table, key) in PATH_KEYS:
                value = (
                    [str((base / v).resolve()) for v in value]
                    if isinstance(value, list)
                    else str((base / value).resolve())
                )
            config[table][key] = value
    return config


def check_config(raw: dict, label: str) -> None:
    """Raise InputError naming the first unknown table or key, or wrongly typed value."""
    for table, values in raw.items():
        if table not in SCHEMA:
            raise InputError(f"{label}: unknown table [{table}]; the tables are {', '.join(SCHEMA)}")
        if not isinstance(values, dict):
            raise InputError(f"{label}: '{table}' must be a table ([{table}])")
        for key, value in values.items():
            if key not in SCHEMA[table]:
                known = ", ".join(SCHEMA[table])
                raise InputError(f"{label}: unknown key '{key}' in [{table}]; known keys: {known}")
            types = SCHEMA[table][key]
            if isinstance(value, bool) and bool not in types:
                raise InputError(f"{label}: [{table}] {key} = {value!r} must be a {types[0].__name__}")
            if not isinstance(value, types):
                raise InputError(f"{label}: [{table}] {key} = {value!r} must be a {types[0].__name__}")
            if types == (list,) and not all(isinstance(v, str) for v in value):
                raise InputError(f"{label}: [{table}] {key} must be a list of strings")


def override(config: dict, table: str, key: str, value: Any) -> None:
    """Set a value from the command line when it was given."""
    if value is not None:
        config[table][key] = value
