"""Exported run-time routines: the switching rule for controllers and other runtimes.

Every target renders the same :class:`groupfit.runtime.RuleTables` and
performs the operations of :class:`groupfit.runtime.SwitchingRule` in the
same order:

* ``c``: ``groupfit_model.h`` / ``groupfit_model.c`` (C99, no heap, const tables);
* ``st``: one IEC 61131-3 Structured Text FUNCTION_BLOCK (REAL or LREAL);
* ``json``: the tables and rule parameters for any other runtime;
* ``sheet``: how the output maps onto a controller (SINUMERIK and integer forms).

:func:`render` returns ``{file name: text}`` without touching the disk;
:func:`write` writes those files, all of them or none.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from groupfit.errors import InputError
from groupfit.export.c import render_c
from groupfit.export.c_probe import with_probe
from groupfit.export.cec import cec_options, render_cec
from groupfit.export.json_table import render_json
from groupfit.export.sheet import render_sheet
from groupfit.export.st import render_st
from groupfit.export.table import DEFAULT_TABLE_TOLERANCE_UM, render_table
from groupfit.io import atomic_write_files
from groupfit.model import ModelFile
from groupfit.runtime import RuleTables

TARGETS = ("c", "st", "json", "sheet")


def render(model: ModelFile | Mapping[str, Any], target: str, **options) -> dict[str, str]:
    """The files of one export target, as ``{file name: text}``.

    Options: ``real`` ("REAL" or "LREAL") and ``name`` (block name) for
    ``st``; ``resolution_um`` and ``counts_limit`` for ``sheet``; ``tolerance_um``
    for ``table`` (the equidistant position table of a position model,
    :func:`groupfit.export.table.render_table`); ``state``, ``table_index``,
    ``input_axis``, ``output_axis``, ``step_mm``, ``tolerance_um`` and
    ``max_points`` for ``cec`` (a SINUMERIK compensation table,
    :func:`groupfit.export.cec.render_cec`).
    """
    tables = RuleTables.from_model(ModelFile.coerce(model).checked())
    if target == "c":
        return with_probe(render_c(tables), tables)
    if target == "st":
        return render_st(tables, real=options.get("real", "LREAL"), name=options.get("name", "FB_GroupfitComp"))
    if target == "json":
        return render_json(tables)
    if target == "sheet":
        return render_sheet(
            tables,
            resolution_um=options.get("resolution_um", 0.1),
            counts_limit=options.get("counts_limit", 30000),
        )
    if target == "table":
        return render_table(
            ModelFile.coerce(model).checked(),
            tolerance_um=options.get("tolerance_um", DEFAULT_TABLE_TOLERANCE_UM),
            name=options.get("name", "FB_GroupfitComp"),
            real=options.get("real", "LREAL"),
        )
    if target == "cec":
        return render_cec(ModelFile.coerce(model).checked(), **cec_options(options))
    raise InputError(f"export target {target!r}: choose one of {', '.join(TARGETS)}")


def write(files: dict[str, str], out_dir: str | Path) -> list[Path]:
    """Write rendered files into ``out_dir``; return their paths."""
    out_dir = Path(out_dir)
    return atomic_write_files({out_dir / name: text for name, text in files.items()})


__all__ = ["TARGETS", "render", "write"]
