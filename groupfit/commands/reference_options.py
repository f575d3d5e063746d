"""``--reference`` and ``--ambient``: what a model's temperature inputs are taken relative to."""

from __future__ import annotations

import argparse

from groupfit.commands.common import report_stream
from groupfit.data import Run
from groupfit.default_columns import ambient_columns
from groupfit.errors import InputError
from groupfit.reference import AMBIENT_COLUMN, default_reference, refuse_as_temperature
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


def configured_reference(args: argparse.Namespace, settings: RunSettings, run: Run) -> str | None:
    """The reference of ``--reference``, else ``[model] reference``, else ``--ambient``, else the run's
    ambient (:func:`groupfit.reference.default_reference`); a note says which ambient was found by its name."""
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
    if value is None and AMBIENT_COLUMN not in run.frame.columns:
        note = _ambient_note(run, reference)
        if note:
            print(f"note    {note}", file=report_stream(args))
    return reference


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
