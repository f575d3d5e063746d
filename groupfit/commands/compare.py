"""``groupfit compare``: grouped p = 0…P against global MLR and physics AR(1), on every run."""

from __future__ import annotations

import argparse
from typing import Any

from groupfit.commands.common import (
    StageProgress,
    add_data_options,
    check_output_dir,
    config_with_data_options,
    load_configured_run,
    report_stream,
    write_json,
)
from groupfit.comparison import ComparisonResult, ComparisonSettings, compare_models
from groupfit.config import default_config_path, ga_settings, override
from groupfit.errors import InputError
from groupfit.inference.cli import add_interval_options, interval_notes, interval_settings

MODEL_LABELS = {"mlr": "MLR (p = 0)", "ar1": "AR(1) free run"}


def add_parser(verbs) -> None:
    compare = verbs.add_parser("compare", help="grouped p = 0…P vs global MLR vs physics AR(1) on all runs")
    compare.add_argument(
        "config", nargs="?", metavar="CONFIG", help="TOML run configuration (default configs/default.toml)"
    )
    add_data_options(compare)
    compare.add_argument("--validate", nargs="+", metavar="CSV", help="validation runs (not used for fitting)")
    compare.add_argument("--pmax", type=int, help="largest number of breaks compared (default 4)")
    compare.add_argument("--seed", type=int, help="seed of the genetic algorithm")
    compare.add_argument("--json", metavar="FILE", help="write the result as JSON ('-' for stdout)")
    compare.add_argument("--out", metavar="DIR", help="folder for the figures")
    compare.add_argument("--quiet", action="store_true", help="no progress bar")
    add_interval_options(compare)
    compare.set_defaults(handler=run_compare)


def settings_from_config(config: dict) -> ComparisonSettings:
    model, table = config["model"], config["compare"]
    return ComparisonSettings(
        pmax=table["pmax"],
        n=model["n"],
        c=float(model["c"]),
        objective=model["objective"],
        fit_intercept=model["intercept"],
        seed=config["search"]["seed"],
        heat=table["heat"],
        ar1_scaling=table["ar1_scaling"],
        heat_exponent=float(table.get("heat_exponent", 5 / 3)),
        rise_sensor=table.get("rise_sensor"),
        rise_window_s=float(table.get("rise_window_s", 6000.0)),
        structural_sensor=table.get("structural_sensor"),
        structural_gain_um_per_K=table.get("structural_gain_um_per_K"),
        conditions=tuple(table["conditions"]),
        p_target=table.get("p_target"),
        ga=ga_settings(config),
    )


def run_compare(args: argparse.Namespace) -> int:
    config = config_with_data_options(args, args.config or default_config_path())
    override(config, "data", "validate", args.validate)
    override(config, "compare", "pmax", args.pmax)
    override(config, "search", "seed", args.seed)
    override(config, "output", "dir", args.out)
    settings = settings_from_config(config)
    settings.intervals = interval_settings(args)
    if settings.structural_sensor and settings.structural_gain_um_per_K is None:
        raise InputError("[compare] structural_sensor needs structural_gain_um_per_K (µm per K, e.g. α·L)")

    modelling = load_configured_run(config)
    validation = [load_configured_run(config, path) for path in config["data"]["validate"]]
    out_dir = check_output_dir(config["output"]["dir"])
    progress = StageProgress(enabled=not args.quiet)
    try:
        result = compare_models(modelling, validation, settings, live_rule=live_switching_rule(), progress=progress)
    finally:
        progress.close()

    from groupfit.plots import plot_r_against_p, plot_run_comparison

    written = []
    for run in [modelling, *validation]:
        figure = out_dir / f"compare_{run.name}.png"
        role = "modelling run" if run is modelling else f"validation run, grouped by {result.validation_rule}"
        plot_run_comparison(
            run.time,
            run.error,
            result.predictions[run.name],
            figure,
            f"{run.name} ({role})",
            bands=result.bands[run.name],
        )
        written.append(figure)
    figure = out_dir / "R_against_p.png"
    plot_r_against_p(result.path["R"], result.rows, result.runs, figure)
    written.append(figure)

    write_json(args.json, result_json(result))
    print(compare_report(result, written), file=report_stream(args))
    return 0


def live_switching_rule():
    """The run-time switching rule as ``(model_dict, temps) -> 0-based groups``, when available."""
    try:
        from groupfit.switching import replay_groups
    except ImportError:
        return None
    return replay_groups


def result_json(result: ComparisonResult) -> dict[str, Any]:
    return {
        "runs": result.runs,
        "rows": result.rows,
        "p_selection": result.selection,
        "exact_path": {k: result.path[k] for k in ("breaks", "objective", "R", "rss")},
        "break_stability": result.break_stability,
        "condition_changes": result.condition_changes,
        "mlr_statistics": result.mlr_statistics,
        "ar1": result.ar1,
        "validation_grouping": result.validation_rule,
        "break_intervals": {str(p): report.to_json() for p, report in result.break_intervals.items()},
    }


def compare_report(result: ComparisonResult, written) -> str:
    """The comparison table and its notes, as printed."""
    modelling = result.runs[0]
    keys = ["mlr", "ar1"] + sorted(
        {f"grouped{r['p']}" for r in result.rows if r["model"] == "grouped"}, key=lambda k: int(k[7:])
    )
    index = {(r["model"] if r["model"] != "grouped" else f"grouped{r['p']}", r["run"]): r for r in result.rows}
    header_runs = ["model".ljust(16)]
    header_cols = [" " * 16]
    for i, run in enumerate(result.runs):
        label = f"{run} ({'modelling' if i == 0 else 'validation'})"
        header_runs.append(label[:34].center(34))
        header_cols.append(f"{'R mm':>8}{'R µm':>9}{'RMS':>8}{'max|e|':>9}")
    lines = ["  ".join(header_runs), "  ".join(header_cols)]
    for key in keys:
        name = MODEL_LABELS.get(key, f"grouped p = {key[7:]}")
        cells = [name.ljust(16)]
        for run in result.runs:
            r = index[(key, run)]
            cells.append(f"{r['R_mm']:>8.4f}{r['R_um']:>9.2f}{r['rms_um']:>8.3f}{r['max_um']:>9.3f}")
        lines.append("  ".join(cells))
    lines += [
        "",
        f"breaks on {modelling} (distance in samples to the nearest change of operating condition at "
        f"{result.condition_changes}):",
    ]
    for key in keys[2:]:
        r = index[(key, modelling)]
        report = result.break_intervals.get(r["p"])
        cis = [f" {report.text_for(b)}" if report is not None and report.intervals else "" for b in r["breaks"]]
        pairs = ", ".join(f"{b}{ci} ({d})" for b, ci, d in zip(r["breaks"], cis, r["break_distance"]))
        lines.append(f"  p = {r['p']}: {pairs}")
    lines += interval_notes(result.break_intervals)
    stability = ", ".join(f"p {s['from_p']}→{s['to_p']}: {s['max_shift']}" for s in result.break_stability)
    lines.append(f"break stability (largest move of an existing break when p grows, samples): {stability or '-'}")
    bic, target = result.selection["bic"], result.selection["target"]
    lines.append(
        f"how many breaks: BIC chooses p = {bic['p']}; the target rule (R <= {target['target_um']:.4g} µm) "
        f"chooses p = {target['p'] if target['p'] is not None else 'none up to pmax'}"
    )
    stats = result.mlr_statistics
    terms = ", ".join(
        f"{t['name']} {t['estimate']:.4g} ± {t['std_error']:.2g} (t = {t['t']:.1f})" for t in stats["terms"]
    )
    f_text = f"F = {stats['f_value']:.4g} (p = {stats['f_p_value']:.2g}), " if stats["f_value"] is not None else ""
    lines.append(f"MLR: {terms}; {f_text}R² = {stats['r_squared']:.5f}, σ = {stats['sigma_um']:.3g} µm")
    ar1 = result.ar1
    c2 = ", ".join(f"C2({level}) = {value:.4g} µm" for level, value in ar1["C2"].items())
    lb = ar1["ljung_box"]
    lines.append(
        f"AR(1): C1 = {ar1['C1']:.5f}, {c2}; unseen levels by {ar1['scaling'].replace('_', ' ')}; "
        f"free run from each run's first measured error; "
        f"Ljung–Box Q({lb['lags']}) = {lb['Q']:.1f}, p = {lb['p_value']:.2g}"
    )
    lines.append(
        f"grouped models on validation runs: groups chosen by {result.validation_rule}; "
        "they are fitted to the modelling run's condition and are not retuned."
    )
    lines.append("wrote   " + ", ".join(str(p) for p in written))
    return "\n".join(lines)
