"""The options of single export targets (the ST block's name, the sheet's register, the CEC table's axes), and
the refusal of one the targets written would ignore."""

from __future__ import annotations

import argparse

from groupfit.errors import InputError

TARGET_OPTIONS = {
    "real": ("--real", ("st", "table")),
    "name": ("--name", ("st", "table")),
    "resolution_um": ("--resolution-um", ("sheet",)),
    "counts_limit": ("--counts-limit", ("sheet",)),
    "tolerance_um": ("--tolerance-um", ("table", "cec")),
    "state": ("--state", ("cec",)),
    "table_index": ("--table", ("cec",)),
    "input_axis": ("--base-axis", ("cec",)),
    "output_axis": ("--comp-axis", ("cec",)),
    "step_mm": ("--step", ("cec",)),
    "max_points": ("--max-points", ("cec",)),
}
"""The options of one export target or two: the option and the targets that use it."""


AR1_TARGET_OPTIONS = {"real": ("st",), "name": ("st",)}
"""What the AR(1) model's targets take: its sheet has no integer register, it has no position table."""


def target_options(args: argparse.Namespace, targets, uses: dict | None = None) -> dict:
    """The target options given (the targets' own defaults stand for the rest), refusing one that none of
    ``targets`` takes rather than ignoring it. ``uses``: the targets of each option for this kind of model file
    (an option it lacks takes none), by default the grouped model's (:data:`TARGET_OPTIONS`)."""
    given = {}
    for key, (option, grouped_users) in TARGET_OPTIONS.items():
        value = getattr(args, key, None)
        if value is None:
            continue
        users = grouped_users if uses is None else uses.get(key, ())
        if not set(users) & set(targets):
            if not users:
                raise InputError(f"{option}: no target of this kind of model file takes it; leave it out")
            raise InputError(
                f"{option}: an option of --target {' or '.join(users)}, and --target {args.target} writes none; "
                "leave it out"
            )
        given[key] = value
    return given
