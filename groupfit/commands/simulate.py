"""``groupfit simulate``: write a data set from a scenario configuration."""

from __future__ import annotations

import argparse
from pathlib import Path

from groupfit import fe
from groupfit.commands.common import add_out_option, add_quiet_option, commit_outputs
from groupfit.config import SCHEMA
from groupfit.errors import InputError
from groupfit.io import atomic_write_text
from groupfit.outputs import current_plan
from groupfit.plots import plot_dataset
from groupfit.screw.plots import plot_screw_dataset
from groupfit.synthetic import simulate_lumped
from groupfit.tomlconfig import read_toml

SCENARIO_KINDS = ("headstock", "rod", "ballscrew", "lumped")
"""The models ``simulate`` runs, named by the config's ``kind`` (``"headstock"`` when a non-empty file omits it)."""
KINDS_TEXT = ", ".join(f'"{kind}"' for kind in SCENARIO_KINDS[:-1]) + f' or "{SCENARIO_KINDS[-1]}"'


def read_scenario(path: str | Path) -> dict:
    """The parsed scenario file; an empty one is refused, its model being a default neither README nor SPEC states."""
    config = read_toml(path, "scenario configuration")
    if not config:
        raise InputError(
            f"{path}: the scenario configuration is empty; set kind = {KINDS_TEXT} and its keys (see configs/)"
        )
    run_tables = sorted(RUN_TABLES.intersection(config))
    if "kind" not in config and run_tables:
        raise InputError(
            f"{path}: a run configuration ([{'], ['.join(run_tables)}]), not a scenario; a scenario sets "
            f"kind = {KINDS_TEXT} and its keys (see configs/)"
        )
    return config


def simulate_scenario(config: dict, *, progress: bool):
    """The data set of a parsed scenario: the lumped network or a finite-element model."""
    kind = config.get("kind", "headstock")
    if kind not in SCENARIO_KINDS:
        raise InputError(f"config key 'kind': must be {KINDS_TEXT}, got {kind!r}")
    if kind == "lumped":
        return simulate_lumped(config)
    return fe.simulate_config(config, progress=progress)


RUN_TABLES = frozenset(SCHEMA)
"""Tables of a run configuration (``groupfit fit CONFIG``), which no scenario has."""
CSV_SUFFIXES = (".csv", ".txt", "")
"""Names simulate writes its CSV text under: any other suffix names a format it does not write."""


def add_parser(verbs) -> None:
    simulate = verbs.add_parser("simulate")
    simulate.add_argument("config", metavar="CONFIG", help="TOML scenario configuration")
    add_out_option(simulate, "data set to write (required)", metavar="CSV", required=True)
    add_quiet_option(simulate)
    simulate.set_defaults(handler=run_simulate)


def run_simulate(args: argparse.Namespace) -> int:
    if args.out == "-":
        raise InputError("--out -: simulate writes a data set and its figure; name a CSV file")
    plan = current_plan(force=args.force).read(args.config)
    output = plan.file(args.out, "--out", data=True)
    figure = plan.file(output.with_suffix(".png"), "--out (its figure)")
    if output.suffix.lower() not in CSV_SUFFIXES:
        raise InputError(
            f"--out {args.out}: simulate writes the data set as CSV text, which a {output.suffix} name "
            "would misname (no reader of that format could open it); name a .csv file"
        )
    config = read_scenario(args.config)
    try:
        frame = simulate_scenario(config, progress=not args.quiet)
    except InputError as exc:
        raise InputError(f"{args.config}: {exc}") from None
    atomic_write_text(output, frame.to_csv(index=False, float_format="%.7g", lineterminator="\n"))
    plot = plot_screw_dataset if config.get("kind") == "ballscrew" else plot_dataset
    plot(frame, figure, title=output.stem)
    commit_outputs()
    print(f"wrote {output} ({len(frame)} samples, {len(frame.columns)} columns) and {figure}")
    return 0
