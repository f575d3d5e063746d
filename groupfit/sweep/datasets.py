"""The data files of a sweep study: each file read once, its candidate sensors and the sensor options of the grid
resolved against its columns (:mod:`groupfit.sweep.config` reads the rest of the study)."""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from groupfit.config import parsed_period_tolerance, parsed_temp_range
from groupfit.data import PERIOD_TOLERANCE, TEMP_RANGE_C, load_run
from groupfit.default_columns import DEFAULT_ERROR, DEFAULT_TIME, default_temperature_columns
from groupfit.errors import InputError
from groupfit.heldout.selection import SELECTION_DEFAULTS, SELECTION_METHODS
from groupfit.io import file_sha256
from groupfit.tomlconfig import Table


@dataclass(frozen=True)
class Dataset:
    """One data file of a study.

    Attributes
    ----------
    name : str
        The file stem.
    path : Path
        Absolute path.
    sha256 : str
        Hash of the file's bytes.
    candidates : tuple of str
        Candidate sensor columns, in file order.
    n_samples : int
    columns : tuple of str
        Every column but time and error.
    constant : frozenset of str
        Columns with a single value (never picked by a pattern).
    clock : dict
        ``period_tolerance``, ``resample``, ``drop_glitches`` and ``temp_range`` as :func:`groupfit.data.load_run`
        takes them.
    glitches_left_out : bool
        The error has measuring glitches (:mod:`groupfit.glitches`) and they are left out as not measured.
    notes : tuple of str
        What loading did to the log (a jittering clock accepted, readings resampled).
    """

    name: str
    path: Path
    sha256: str
    candidates: tuple[str, ...]
    n_samples: int
    columns: tuple[str, ...] = field(repr=False, default=())
    constant: frozenset[str] = field(repr=False, default=frozenset())
    clock: dict = field(repr=False, default_factory=lambda: dict(DEFAULT_CLOCK))
    notes: tuple[str, ...] = field(repr=False, default=())
    glitches_left_out: bool = False

    @property
    def clock_spec(self) -> dict:
        """The clock settings that differ from the defaults, as a run's ``data`` holds them (none: no key, so
        that a study without them keeps its runs' hashes)."""
        spec = {}
        if self.clock["period_tolerance"] != PERIOD_TOLERANCE:
            spec["period_tolerance"] = self.clock["period_tolerance"]
        if self.clock["resample"] is not None:
            spec["resample_s"] = self.clock["resample"]
        if self.glitches_left_out:  # the fit changes only where there are glitches: so does the hash
            spec["glitches_left_out"] = True
        return spec


DEFAULT_CLOCK = {
    "period_tolerance": PERIOD_TOLERANCE,
    "resample": None,
    "drop_glitches": True,
    "temp_range": TEMP_RANGE_C,
}


def non_empty_string(value, what: str, label: str) -> str:
    if not isinstance(value, str) or not value:
        raise InputError(f"{label}: {what} = {value!r} must be a non-empty string")
    return value


def read_datasets(table: dict, base: Path, label: str) -> list[Dataset]:
    if "path" in table and "paths" in table:
        raise InputError(f"{label}: [data] has both 'path' and 'paths'; give one of them")
    if "path" in table:
        paths = [non_empty_string(table["path"], "[data] path", label)]
    elif "paths" in table:
        paths = table["paths"]
        if not isinstance(paths, list) or not paths or not all(isinstance(p, str) and p for p in paths):
            raise InputError(f"{label}: [data] paths must be a non-empty list of file names")
    else:
        raise InputError(f'{label}: no data: set [data] path = "run.csv" or paths = ["a.csv", "b.csv"]')
    time_column = non_empty_string(table.get("time", DEFAULT_TIME), "[data] time", label)
    error_column = non_empty_string(table.get("error", DEFAULT_ERROR), "[data] error", label)
    patterns = table.get("temps")
    clock = clock_settings(table, label)
    datasets = []
    for entry in paths:
        file = (base / entry).resolve()
        if not file.is_file():
            raise InputError(f"{label}: [data] data file {entry!r} not found (looked for {file})")
        run = load_run(file, temps=[], time=time_column, error=error_column, **{**clock, "drop_glitches": False})
        usable = tuple(c for c in run.frame.columns if c not in (run.time_name, run.error_name))  # as found
        where = f"{label}: {file.name}"
        constant = frozenset(_constant_columns(run.frame, usable))
        roles = {run.time_name: "the run's time", run.error_name: "the thermal error ([data] error)"}
        candidates = candidate_columns(patterns, usable, constant, where, roles)
        checked = load_run(file, temps=candidates, time=time_column, error=error_column, **clock)
        left_out = not np.array_equal(checked.error, run.error, equal_nan=True)
        datasets.append(
            Dataset(
                name=file.stem,
                path=file,
                sha256=file_sha256(file),
                candidates=tuple(candidates),
                n_samples=run.n_samples,
                columns=usable,
                constant=constant,
                clock=clock,
                notes=checked.notes,
                glitches_left_out=left_out,
            )
        )
    names = [d.name for d in datasets]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise InputError(f"{label}: [data] two data files are named '{duplicates[0]}'; rename one")
    return datasets


def clock_settings(table: dict, label: str) -> dict:
    """``[data] period_tolerance`` (percent), ``resample_s`` (seconds), ``keep_glitches`` and ``temp_range``
    (°C) as :func:`groupfit.data.load_run` takes them (``groupfit sweep --period-tolerance``, ``--resample``,
    ``--keep-glitches`` and ``--range-temp`` replace them)."""
    data = Table(table, "data", label)
    tolerance = parsed_period_tolerance(data, "period_tolerance")
    resample = None if table.get("resample_s") is None else data.number("resample_s", positive=True)
    keep = data.boolean("keep_glitches", False)
    temp_range = None if table.get("temp_range") is None else parsed_temp_range(data, "temp_range")
    return {
        "period_tolerance": PERIOD_TOLERANCE if tolerance is None else tolerance,
        "resample": resample,
        "drop_glitches": not keep,
        "temp_range": TEMP_RANGE_C if temp_range is None else temp_range,
    }


def _constant_columns(frame, columns) -> set[str]:
    """Columns with a single value over the run (dead sensors, fixed settings)."""
    constant = set()
    for column in columns:
        values = frame[column]
        if values.nunique(dropna=True) <= 1:
            constant.add(column)
    return constant


def candidate_columns(patterns, usable, constant, label, roles: dict[str, str] | None = None) -> list[str]:
    """Candidate sensor columns, in file order.

    Explicit names must exist; glob patterns (``*``, ``?``, ``[…]``) and the
    default (:func:`groupfit.default_columns.default_temperature_columns`) leave out constant columns.
    ``roles``: the run's columns that are not sensors and what each is (its time, its error).
    """
    roles = roles or {}
    if patterns is None:
        found = [c for c in default_temperature_columns(usable) if c not in constant]
        if not found:
            raise InputError(f"{label}: no temperature columns found; list them in [data] temps")
        return found
    if not isinstance(patterns, list) or not patterns or not all(isinstance(t, str) and t for t in patterns):
        raise InputError(f"{label}: candidate sensors must be a non-empty list of column names or patterns")
    chosen: set[str] = set()
    for pattern in patterns:
        if any(ch in pattern for ch in "*?["):
            matches = [c for c in usable if fnmatch.fnmatchcase(c, pattern) and c not in constant]
            if not matches:
                raise InputError(f"{label}: sensor pattern {pattern!r} matches no (non-constant) column")
        elif pattern in usable:
            matches = [pattern]
        elif pattern in roles:
            raise InputError(f"{label}: column '{pattern}' is {roles[pattern]}, not a sensor")
        else:
            raise InputError(f"{label}: column '{pattern}' not found; the columns are {', '.join(usable)}")
        chosen.update(matches)
    return [c for c in usable if c in chosen]


def sensor_option(option, dataset: Dataset, label: str) -> dict:
    """One value of the sensors dimension, resolved for one data set."""
    where = f"{label}: [grid] sensors"
    if option == "all":
        return {"names": list(dataset.candidates)}
    if isinstance(option, list):
        if not option or not all(isinstance(v, str) and v for v in option):
            raise InputError(f"{where}: {option!r} must be a non-empty list of column names")
        if len(set(option)) != len(option):
            raise InputError(f"{where}: {option!r} names a column twice")
        for name in option:
            if name not in dataset.columns:
                raise InputError(
                    f"{where}: column '{name}' is no input column of {dataset.path.name} (neither the time nor the "
                    f"error is one; the others are {', '.join(dataset.columns)})"
                )
        return {"names": list(option)}
    if isinstance(option, dict):
        return _selection_option(option, dataset, where)
    raise InputError(
        f'{where}: {option!r}: give "all", a list of column names such as ["T1", "T2"], '
        'or a selection such as {select = "forward", k = 4}'
    )


def _selection_option(option: dict, dataset: Dataset, where: str) -> dict:
    known = ("select", "k", "candidates", *SELECTION_DEFAULTS)
    for key in option:
        if key not in known:
            raise InputError(f"{where}: unknown key '{key}' in a selection; known keys: {', '.join(known)}")
    method = option.get("select")
    if method not in SELECTION_METHODS:
        raise InputError(f"{where}: select = {method!r}: choose one of {', '.join(SELECTION_METHODS)}")
    k = option.get("k")
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise InputError(f"{where}: k = {k!r} must be a whole number ≥ 1 (sensors to pick)")
    candidates = list(dataset.candidates)
    if "candidates" in option:
        candidates = candidate_columns(option["candidates"], dataset.columns, dataset.constant, where)
    if k > len(candidates):
        raise InputError(f"{where}: k = {k} but {dataset.path.name} has only {len(candidates)} candidate sensors")
    selection = {"select": method, "k": k, "candidates": candidates}
    for key, default in SELECTION_DEFAULTS.items():
        value = option.get(key, default)
        if isinstance(value, bool) or not isinstance(value, type(default)):
            raise InputError(f"{where}: {key} = {value!r} must be a {type(default).__name__}")
        selection[key] = value
    return selection
