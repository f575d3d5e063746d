"""Read a sweep study (TOML) and expand it into one specification per run.

A study file has up to four tables::

    [study]
    name = "paper-table-1"        # label stored with every run (default: file stem)
    db = "paper_sweep.sqlite"     # study database, relative to this file (default:
                                  #   <file stem>.sqlite in the working folder)
    certify = "auto"              # GA runs also get the exact optimum: "auto" (when
                                  #   cheap), true or false

    [data]
    paths = ["../datasets/synthetic_cycle.csv"]   # or path = "…"; relative to this file
    time = "time_s"
    error = "error_um"
    temps = ["T1", "T2", "node_*"]   # candidate sensors: names or glob patterns
                                     # (default: the columns named T<digit>…)
    period_tolerance = 2             # % an interval may deviate from the period (a jittering clock)
    resample_s = 60                  # average the readings of every 60 s (optional)
    keep_glitches = false            # true: fit on the error's and temperatures' glitches too
    temp_range = [-50, 500]          # plausible temperatures (°C); a reading outside is refused

    [grid]                        # one run per combination of these
    p = {start = 0, stop = 4}     # a range (stop included, optional step) …
    n = [3]                       # … a list …
    c = 3.0                       # … or one value
    objective = ["sae", "sse"]
    intercept = [true]
    search = ["exact", "ga"]
    sensors = ["all", ["T1", "T2"], {select = "forward", k = 4}, {select = "lasso", k = 4}]

    [ga]                          # settings of GA runs only (exact runs ignore them)
    seed = {start = 0, stop = 9}
    population_size = [60]
    max_generations = [50, 300]
    stall_generations = [30]
    polish = [true]
    local_window = [5]            # the Lamarckian shift window (0: off)
    union_crossover = [true]

Every run is a plain, JSON-serialisable dictionary (:attr:`RunSpec.spec`) that
holds everything its result depends on, including the SHA-256 of the data
file's bytes; its hash (:attr:`RunSpec.run_hash`) identifies the run in the
study database, so a changed data file is never mistaken for a run already
done. Unknown tables or keys and values of the wrong type or range raise
:class:`~groupfit.errors.InputError` naming the key.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from groupfit.default_columns import DEFAULT_ERROR, DEFAULT_TIME
from groupfit.errors import InputError
from groupfit.grouping import MAX_SPACING
from groupfit.objective import OBJECTIVES
from groupfit.search.base import GASettings
from groupfit.sweep.datasets import Dataset, non_empty_string, read_datasets, sensor_option
from groupfit.tomlconfig import Table, check_tables, read_toml

SEARCHES = ("exact", "ga")
TABLES = ("study", "data", "grid", "ga")
STUDY_KEYS = ("name", "db", "certify")
DATA_KEYS = (
    "path",
    "paths",
    "time",
    "error",
    "temps",
    "period_tolerance",
    "resample_s",
    "keep_glitches",
    "temp_range",
)
GRID_DEFAULTS: dict[str, list[Any]] = {
    "p": [3],
    "n": [3],
    "c": [3.0],
    "objective": ["sae"],
    "intercept": [True],
    "search": ["exact"],
    "sensors": ["all"],
}
GA_GRID_DEFAULTS: dict[str, list[Any]] = {
    "seed": [0],
    **{key: [value] for key, value in GASettings().as_dict().items()},
}
RANGE_KEYS = ("start", "stop", "step")
MAX_STUDY_RUNS = 100_000
"""Most runs a study may hold (every combination of its grid): a larger one is refused before it is expanded."""


@dataclass(frozen=True)
class RunSpec:
    """One run of a study."""

    spec: dict
    """Everything the result depends on: ``data`` (sha256, time, error columns), ``sensors`` (``{"names":
    […]}`` or a selection), ``model`` (p, n, c, objective, intercept) and ``search`` (method and, for the GA,
    its settings and seed)."""
    path: str
    """The data file (not part of the hash: moving a file keeps its runs)."""
    dataset: str
    """The data file's name, for tables."""
    run_hash: str
    """SHA-256 of the canonical JSON of ``spec``."""


@dataclass
class Study:
    """A parsed study: its data sets and its runs, in grid order."""

    name: str
    source: Path
    db: Path | None
    datasets: list[Dataset]
    runs: list[RunSpec]


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and no spaces: equal objects give equal text."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)


def spec_hash(spec: dict) -> str:
    """The run's identity in the study database."""
    return hashlib.sha256(canonical_json(spec).encode("ascii")).hexdigest()


def read_study(path: str | Path, data: dict | None = None) -> Study:
    """Read, check and expand a study file; ``data``: keys of its ``[data]`` table given on the command line
    (None values left out), in place of the file's.

    Raises
    ------
    InputError
        Naming the file and the key or value at fault.
    """
    path = Path(path)
    raw = read_toml(path, "sweep configuration")
    given = {key: value for key, value in (data or {}).items() if value is not None}
    if given:
        raw = {**raw, "data": {**raw.get("data", {}), **given}}
    return study_from_dict(raw, path)


def study_from_dict(raw: dict, path: Path) -> Study:
    """Expand an already parsed study; relative paths are taken against ``path``'s folder."""
    label = str(path)
    base = path.resolve().parent
    check_tables(raw, TABLES, label)
    study_table = _checked_table(raw, "study", STUDY_KEYS, label)
    data_table = _checked_table(raw, "data", DATA_KEYS, label)
    grid_table = _checked_table(raw, "grid", tuple(GRID_DEFAULTS), label)
    ga_table = _checked_table(raw, "ga", tuple(GA_GRID_DEFAULTS), label)

    name = non_empty_string(study_table.get("name", path.stem), "[study] name", label)
    db = study_table.get("db")
    db_path = (base / non_empty_string(db, "[study] db", label)).resolve() if db is not None else None
    certify = study_table.get("certify", "auto")
    if certify != "auto" and not isinstance(certify, bool):
        raise InputError(f'{label}: [study] certify = {certify!r} must be "auto", true or false')

    datasets = read_datasets(data_table, base, label)
    time_column = data_table.get("time", DEFAULT_TIME)
    error_column = data_table.get("error", DEFAULT_ERROR)
    grid = {key: _dimension(grid_table, key, label, GRID_DEFAULTS[key]) for key in GRID_DEFAULTS}
    ga = {key: _dimension(ga_table, key, label, GA_GRID_DEFAULTS[key]) for key in GA_GRID_DEFAULTS}

    size = len(datasets) * math.prod(map(len, grid.values())) * math.prod(map(len, ga.values()))
    if size > MAX_STUDY_RUNS:
        raise InputError(
            f"{label}: the grid makes up to {size:g} runs, more than {MAX_STUDY_RUNS}: narrow [grid] or [ga]"
        )
    runs: list[RunSpec] = []
    seen: set[str] = set()
    for dataset in datasets:
        data = {"sha256": dataset.sha256, "time": time_column, "error": error_column, **dataset.clock_spec}
        sensor_options = [sensor_option(option, dataset, label) for option in grid["sensors"]]
        for sensors, objective, intercept, n, c, p, search in itertools.product(
            sensor_options, grid["objective"], grid["intercept"], grid["n"], grid["c"], grid["p"], grid["search"]
        ):
            model = {"p": p, "n": n, "c": float(c), "objective": objective, "intercept": intercept}
            # with no break there is nothing to search: a GA run at p = 0 is the exact run
            for search_spec in _search_specs("exact" if p == 0 else search, ga, certify):
                spec = {"data": data, "sensors": sensors, "model": model, "search": search_spec}
                run_hash = spec_hash(spec)
                if run_hash in seen:
                    continue
                seen.add(run_hash)
                runs.append(
                    RunSpec(
                        spec=json.loads(canonical_json(spec)),
                        path=str(dataset.path),
                        dataset=dataset.name,
                        run_hash=run_hash,
                    )
                )
    return Study(name=name, source=path, db=db_path, datasets=datasets, runs=runs)


def _search_specs(method: str, ga: dict[str, list], certify) -> list[dict]:
    if method == "exact":
        return [{"method": "exact"}]
    keys = (*GASettings().as_dict(), "seed")
    return [
        {"method": "ga", "certify": certify, **dict(zip(keys, values))}
        for values in itertools.product(*(ga[key] for key in keys))
    ]


def _checked_table(raw: dict, table: str, keys: tuple[str, ...], label: str) -> dict:
    checked = Table(raw.get(table, {}), table, label)
    for key in keys:
        checked.get(key)
    checked.finish(f"known keys: {', '.join(keys)}")
    return checked.data


def _dimension(table: dict, key: str, label: str, default: list) -> list:
    """The values of one sweep dimension: a list, a range table or a single value."""
    what = f"[{'ga' if key in GA_GRID_DEFAULTS else 'grid'}] {key}"
    if key not in table:
        return list(default)
    raw = table[key]
    if key == "sensors":
        options = raw if isinstance(raw, list) and not _is_name_list(raw) else [raw]
        if isinstance(raw, list) and not raw:
            raise InputError(f"{label}: {what} is empty; give at least one value")
        return options
    if isinstance(raw, dict):
        values = _expand_range(raw, what, label)
    elif isinstance(raw, list):
        values = raw
    else:
        values = [raw]
    if not values:
        raise InputError(f"{label}: {what} is empty; give at least one value")
    check = VALUE_CHECKS[key]
    checked = [check(v, f"{what} value {v!r}", label) for v in values]
    unique = []
    for v in checked:
        if v not in unique:
            unique.append(v)
    return unique


def _is_name_list(raw: list) -> bool:
    """``sensors = ["T1", "T2"]`` is one subset, unless its strings are options such as "all"."""
    return bool(raw) and all(isinstance(v, str) for v in raw) and "all" not in raw


def _expand_range(raw: dict, what: str, label: str) -> list:
    for key in raw:
        if key not in RANGE_KEYS:
            raise InputError(f"{label}: {what}: unknown key '{key}' in a range; use start, stop and step")
    if "start" not in raw or "stop" not in raw:
        raise InputError(f"{label}: {what}: a range needs start and stop (stop is included)")
    start, stop, step = raw["start"], raw["stop"], raw.get("step", 1)
    for name, value in (("start", start), ("stop", stop), ("step", step)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(f"{label}: {what}: range {name} = {value!r} must be a number")
    if step <= 0:
        raise InputError(f"{label}: {what}: range step = {step!r} must be positive")
    if stop < start:
        raise InputError(f"{label}: {what}: range stop = {stop!r} is below start = {start!r}")
    count = int(math.floor((stop - start) / step + 1e-9)) + 1
    if count > MAX_STUDY_RUNS:
        raise InputError(
            f"{label}: {what}: the range holds {count:g} values, more than a study's {MAX_STUDY_RUNS} runs"
        )
    if all(isinstance(v, int) for v in (start, stop, step)):
        return [start + i * step for i in range(count)]
    return [round(start + i * step, 12) for i in range(count)]


LARGEST_INTEGER = 2**63 - 1
"""The largest whole number the study's database (SQLite INTEGER) and a TOML integer hold."""


def _integer(minimum: int) -> Callable:
    def check(value, what: str, label: str) -> int:
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int) or not minimum <= value <= LARGEST_INTEGER:
            raise InputError(f"{label}: {what} must be a whole number from {minimum} to {LARGEST_INTEGER}")
        return value

    return check


def _number(value, what: str, label: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise InputError(f"{label}: {what} must be a finite number ≥ 0")
    return float(value)


def _spacing(value, what: str, label: str) -> float:
    value = _number(value, what, label)
    if value > MAX_SPACING:
        raise InputError(f"{label}: {what} must be a number from 0 to {MAX_SPACING:g}")
    return value


def _choice(choices: tuple[str, ...]) -> Callable:
    def check(value, what: str, label: str) -> str:
        if value not in choices:
            raise InputError(f"{label}: {what}: choose one of {', '.join(choices)}")
        return value

    return check


def _boolean(value, what: str, label: str) -> bool:
    if not isinstance(value, bool):
        raise InputError(f"{label}: {what} must be true or false")
    return value


VALUE_CHECKS: dict[str, Callable] = {
    "p": _integer(0),
    "n": _integer(0),
    "c": _spacing,
    "objective": _choice(OBJECTIVES),
    "intercept": _boolean,
    "search": _choice(SEARCHES),
    "seed": _integer(0),
    "population_size": _integer(2),
    "max_generations": _integer(1),
    "stall_generations": _integer(1),
    "polish": _boolean,
    "local_window": _integer(0),
    "union_crossover": _boolean,
}
