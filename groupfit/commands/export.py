"""``groupfit export``: the run-time switching rule for a controller or another runtime."""

from __future__ import annotations

import argparse

from groupfit.ar1.modelfile import is_ar1_file
from groupfit.commands import ar1 as ar1_commands
from groupfit.commands import common
from groupfit.commands.export_options import target_options
from groupfit.commands.screw_deploy import run_screw_export
from groupfit.errors import InputError
from groupfit.export import TARGETS, render
from groupfit.export.cec import DEFAULT_MAX_POINTS
from groupfit.model import ModelFile
from groupfit.runtime.period import at_period
from groupfit.screw.modelfile import is_screw_file


def add_parser(verbs) -> None:
    export = verbs.add_parser("export")
    common.add_model_argument(export)
    export.add_argument(
        "--target",
        required=True,
        choices=(*TARGETS, "table", "cec", "all"),
        help="c: groupfit_model.h/.c (C99); st: IEC 61131-3 function block; json: tables for any runtime; "
        "sheet: controller sheet (text and JSON); table: the equidistant position table of a position model "
        "(C, ST and CSV); cec: a SINUMERIK 840D compensation table (NC_CEC.INI) of a position model at one "
        "thermal state (--state); all: every target (with table for a position model)",
    )
    common.add_out_option(export, "folder for the exported files (required)", required=True)
    common.add_quiet_option(export)
    export.add_argument("--real", choices=("REAL", "LREAL"), help="st, table: real type (default LREAL)")
    export.add_argument(
        "--name", help="st, table: function block name (default FB_GroupfitComp; AR(1): FB_GroupfitAR1)"
    )
    resolution = "µm per count of an integer compensation register (default 0.1)"
    common.add_register_options(export, resolution, target="sheet: ")
    export.add_argument(
        "--tolerance-um",
        type=float,
        metavar="UM",
        help="table, cec: largest interpolation error of the position table (default 0.5 um)",
    )
    add_cec_options(export)
    common.add_source_option(export)
    export.add_argument(
        "--period",
        type=float,
        metavar="S",
        help="the controller's sampling period (s), when it differs from the model's: a model without breaks "
        "is rescaled to it (its lags keep their time constants); one with breaks is refused",
    )
    export.set_defaults(handler=run_export)


def add_cec_options(export) -> None:
    cec = export.add_argument_group("cec (SINUMERIK compensation table)")
    cec.add_argument(
        "--state",
        metavar="NAME=VALUE,...",
        help="cec: the thermal state of the table, every model input (rises over the reference when it has one)",
    )
    cec.add_argument("--table", dest="table_index", type=int, metavar="T", help="cec: table index (0)")
    cec.add_argument("--base-axis", dest="input_axis", metavar="AXIS", help="cec: the base axis (AX1)")
    cec.add_argument(
        "--comp-axis", dest="output_axis", metavar="AXIS", help="cec: the compensated axis (default: the base axis)"
    )
    cec.add_argument(
        "--step", dest="step_mm", type=float, metavar="MM", help="cec: point spacing (default: from --tolerance-um)"
    )
    cec.add_argument(
        "--max-points",
        type=int,
        metavar="N",
        help=f"cec: most points of a table, MD18342 (default {DEFAULT_MAX_POINTS})",
    )


def run_export(args: argparse.Namespace) -> int:
    if is_screw_file(args.model):
        return run_screw_export(args)
    if is_ar1_file(args.model):
        return ar1_commands.run_export(args)
    common.plan_outputs(args, args.model, folder=args.out)
    model = ModelFile.load(args.model)
    if args.period is not None:
        try:
            model = at_period(model, args.period)
        except InputError as exc:
            raise InputError(f"{args.model}: {exc}") from None
    targets = TARGETS if args.target == "all" else (args.target,)
    if args.target == "all" and model.position is not None:
        targets = (*TARGETS, "table")
    options = target_options(args, targets)
    files: dict[str, str] = {}
    for target in targets:
        files.update(render(model, target, **options))
    common.write_exports(args, files)
    return 0


__all__ = ["run_export"]
