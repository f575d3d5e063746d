"""A log of JSON records as a table: one row per record, one column per value.

Machines and their web interfaces log in JSON: one object per line (JSON
lines, ``.jsonl``; a 3-D printer's ``{"ts": …, "btemp": 25.8, "z": 0.01}``), an
array of objects, an object of columns (``{"time_s": […], "T1": […]}``) or an
object that holds one such array (``{"machine": "…", "samples": […]}``).

A nested value is a column named by its path: ``{"spindle": {"T": 31.2}}`` is
column ``spindle.T``; a list of objects that name themselves
(``"atherms": [{"id": "C", "temp": 26.6}]``) gives ``atherms.C.temp``, other
lists their positions (``T.0``, ``T.1``). Records of several kinds (a
temperature record every 20 s, a probe reading every 2 s) leave each
other's columns empty; the loader averages them onto the slowest kind's
period (:mod:`groupfit.record_kinds`), as ``--resample`` does a logger's CSV.
"""

from __future__ import annotations

import json
from typing import Any

import pandas as pd

from groupfit.errors import InputError
from groupfit.io import json_integer
from groupfit.textencoding import decode

SELF_NAMES = ("id", "name", "sensor", "channel", "label")
"""Keys by which an object in a list names itself (``{"id": "C", "temp": 26.6}``): its values are named by it."""


def read_json_log(content: bytes, label: str, encoding: str | None = None) -> pd.DataFrame:
    """The table of a JSON log's records (module docstring).

    Raises
    ------
    InputError
        Not JSON (the line and what is wrong named), or JSON that holds no records.
    """
    text = decode(content, encoding).lstrip("\ufeff")
    if not text.strip():
        raise InputError(f"{label}: the file is empty; one JSON record per sample is needed")
    try:
        document = json.loads(text, parse_int=json_integer)
    except json.JSONDecodeError as exc:
        if exc.msg != "Extra data":
            raise InputError(f"{label}: line {exc.lineno}: not JSON ({exc.msg}); fix or remove that line") from None
        return _table(_json_lines(text, label), label)
    return _table(_records(document, label), label)


def _json_lines(text: str, label: str) -> list[dict]:
    records = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line, parse_int=json_integer)
        except json.JSONDecodeError as exc:
            raise InputError(
                f"{label}: line {number}: not a JSON record ({exc.msg}); fix or remove that line"
            ) from None
        if not isinstance(record, dict):
            raise InputError(
                f'{label}: line {number}: a JSON {type(record).__name__}, not a record ({{"name": value, …}}); '
                "fix or remove that line"
            )
        records.append(record)
    return records


def _records(document: Any, label: str) -> list[dict]:
    """The records of a JSON document: an array of objects, an object of equal-length columns, or the longest
    array of objects an object holds."""
    if isinstance(document, list) and document and all(isinstance(item, dict) for item in document):
        return document
    if isinstance(document, dict):
        columns = {key: value for key, value in document.items() if isinstance(value, list)}
        lengths = {len(value) for value in columns.values()}
        scalars = all(not isinstance(v, (dict, list)) for value in columns.values() for v in value)
        if len(document) == len(columns) >= 2 and len(lengths) == 1 and scalars:
            (n,) = lengths
            return [{key: value[i] for key, value in columns.items()} for i in range(n)]
        arrays = [value for value in columns.values() if value and all(isinstance(item, dict) for item in value)]
        if arrays:
            return max(arrays, key=len)
    raise InputError(
        f"{label}: JSON without records: groupfit reads one object per sample (JSON lines, or an array of "
        "objects), or an object of columns of equal length; convert the log to a CSV table with a header and "
        "one row per sample"
    )


def _table(records: list[dict], label: str) -> pd.DataFrame:
    rows = [_flat(record) for record in records]
    if not rows:
        raise InputError(f"{label}: the file holds no records; one JSON record per sample is needed")
    return pd.DataFrame(rows)  # columns in the order they first appear, as pandas lays out a list of dicts


def _flat(value: Any, path: str = "", into: dict | None = None) -> dict:
    """``{column path: scalar}`` of one record (module docstring)."""
    into = {} if into is None else into
    if isinstance(value, dict):
        for key, item in value.items():
            _flat(item, f"{path}.{key}" if path else str(key), into)
    elif isinstance(value, list):
        for position, item in enumerate(value):
            name = _self_name(item)
            if name is None:
                _flat(item, f"{path}.{position}", into)
            else:
                rest = {key: v for key, v in item.items() if key != name[0]}
                _flat(rest, f"{path}.{name[1]}", into)
    else:
        into[path] = float(value) if isinstance(value, bool) else value
    return into


def _self_name(item: Any) -> tuple[str, str] | None:
    """``(key, name)`` by which an object in a list names itself; None for anything else."""
    if not isinstance(item, dict):
        return None
    for key in SELF_NAMES:
        if isinstance(item.get(key), str) and item[key].strip():
            return key, item[key].strip()
    return None


__all__ = ["read_json_log"]
