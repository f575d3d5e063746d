"""``--reference`` and ``--ambient``: what a model's temperature inputs are taken relative to."""

from __future__ import annotations

import argparse
from typing import Sequence

from groupfit.commands.common import report_stream
from groupfit.data import Run
from groupfit.default_columns import ambient_columns
from groupfit.errors import InputError
from groupfit.reference import (
    AMBIENT_COLUMN,
    default_reference,
    is_column_reference,
    refuse_as_temperature,
    with_reference,
)
from groupfit.settings import RunSettings


def add_reference_option(parser: argparse.ArgumentParser) -> None:
    """``--reference COLUMN|start|none``: what the model's temperature inputs are taken relative to."""
    parser.add_argument(
        "--reference",
        metavar="COLUMN|start|none",
        help="take every input minus a reference sensor (e.g. T_amb), minus its first reading ('start'), "
        "or as read ('none'); default: the --ambient column, else T_amb when the run has that column, else the "
        "one column named as the air's temperature (Room [°C], Ambient), else none",
    )
    parser.add_argument(
        "--ambient",
        metavar="COLUMN",
        help="the ambient temperature, whatever its name (an air sensor logged as T15): never a default input, "
        "and the default reference (default: T_amb, else the one column named as the air's temperature)",
    )


def reference_is_default(args: argparse.Namespace, settings: RunSettings) -> bool:
    """Whether neither ``--reference`` nor ``[model] reference`` names the reference."""
    return getattr(args, "reference", None) is None and settings.model.reference is None


def configured_reference(
    args: argparse.Namespace, settings: RunSettings, run: Run, parts: Sequence[Run] = ()
) -> str | None:
    """The reference of ``--reference``, else ``[model] reference``, else ``--ambient``, else the run's
    ambient (:func:`groupfit.reference.default_reference`); a note says which ambient was found by its name.
    ``parts``: the runs ``run`` joins, named when some lack the column (the joined run keeps shared columns)."""
    lacking = _lacking(parts, getattr(args, "reference", None) or settings.model.reference or settings.data.ambient)
    if lacking:
        column, names = lacking
        raise InputError(
            f"{names}: no column '{column}', which the other runs have and the inputs are to be taken over; give "
            "every run the column, or leave those runs out"
        )
    value = getattr(args, "reference", None)
    given = "--reference"
    if value is None:
        value, given = settings.model.reference, "[model] reference"
    ambient = settings.data.ambient
    if value is not None and not str(value).strip():
        raise InputError(f"{given} is empty: name a column ('none' reads the inputs as logged, 'start' over the start)")
    if ambient is not None and not str(ambient).strip():
        raise InputError("the ambient column is empty (--ambient, [data] ambient): name the air's column")
    if value is None and ambient is not None:
        if ambient not in run.frame.columns:
            available = ", ".join(map(str, run.frame.columns))
            raise InputError(f"{run.source}: --ambient column '{ambient}' not found; the columns are: {available}")
        refuse_as_temperature(run, ambient, "--ambient column")
        value = ambient
    reference = default_reference(run.frame, value, run.temp_names)
    lacking = _lacking(parts, AMBIENT_COLUMN) if value is None and reference is None else None
    if lacking:
        column, names = lacking
        print(
            f"note    {names}: no {column} column, which the other runs have: the inputs of every run are read as "
            f"logged (absolute); give every run its {column} column to take the inputs over it",
            file=report_stream(args),
        )
    if value is None and AMBIENT_COLUMN not in run.frame.columns:
        note = _ambient_note(run, reference)
        if note:
            print(f"note    {note}", file=report_stream(args))
    for part in parts if len(parts) > 1 else ():
        with_reference(part, reference)  # a gap in one run's reference is named by that run's own row
    return reference


def _lacking(parts: Sequence[Run], column) -> tuple[str, str] | None:
    """``(column, the sources of the parts without it)`` when some of ``parts`` have ``column`` and some do not."""
    if not isinstance(column, str) or not is_column_reference(column) or len(parts) < 2:
        return None
    without = [part.source for part in parts if column not in part.frame.columns]
    return (column, ", ".join(without)) if without and len(without) < len(parts) else None


def _ambient_note(run: Run, reference: str | None) -> str | None:
    if reference is not None:
        return (
            f"reference '{reference}': the run's ambient, found by its name; the inputs are taken over it, as over "
            "T_amb (--reference none reads them as logged, --ambient COLUMN names another)"
        )
    found = ambient_columns(run.frame, run.temp_names)
    if len(found) > 1:
        return (
            f"several columns are named as the air's temperature ({', '.join(found)}): none is taken as the "
            "reference; --ambient COLUMN names the one the inputs are taken over"
        )
    return None
