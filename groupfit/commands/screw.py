"""``groupfit screw``: the ball-screw temperature-field model of seed 003.

Sub-verbs:

* ``identify RUN…`` — h, α′(τ0) and C1, C2 of the first run's source from its
  steady profile and transient; C1, C2 of every further run's source from its
  first t_r seconds; writes the model file (kind ``ballscrew``);
* ``predict MODEL --data RUN`` — temperature rises at the sensors and the
  thermal error at the probe, with the seed's error metrics;
* ``compare RUN --validate RUN…`` — the screw model against an MLR on the same
  sensors, scored on every run against the FE data.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.commands import common
from groupfit.errors import InputError
from groupfit.io import refuse_repeated
from groupfit.outputs import SCREW_MODELS, resolved_path
from groupfit.screw import BallScrewModel
from groupfit.screw.compare import compare_screw, paper_bounds, paper_columns, paper_label, paper_notes, score_screw
from groupfit.screw.modelfile import load_model, model_to_dict, save_model
from groupfit.screw.plots import plot_error, plot_rises
from groupfit.screw.runs import PROBE_COLUMN, load_screw_run, probe_reach_m

DEFAULT_OUT = "groupfit-out"


def add_parser(verbs) -> None:
    screw = verbs.add_parser("screw", help="ball-screw temperature field and thermal error (seed 003)")
    sub = screw.add_subparsers(dest="screw_verb", required=True, metavar="SUBVERB", parser_class=type(screw))

    identify = sub.add_parser("identify", help="identify h, α′(τ0) and C1, C2 per source from heating runs")
    identify.add_argument("runs", nargs="+", metavar="RUN", help="first: the identification run; then new sources")
    _model_options(identify)
    _output_options(
        identify, "write the model as JSON also here", f"folder for screw_model.json (default {DEFAULT_OUT})"
    )
    identify.set_defaults(handler=run_identify)

    predict = sub.add_parser("predict", help="temperature field and thermal error of a run, with the seed's metrics")
    predict.add_argument("model", metavar="MODEL", help="ball-screw model file (screw identify)")
    predict.add_argument("--data", required=True, metavar="CSV", help="the run")
    predict.add_argument(
        "--source",
        metavar="NAME",
        help="use this source's C1, C2 (default: the run's name if the model has it, "
        "else re-identified from the run's first t_r seconds)",
    )
    predict.add_argument("--probe-x", type=float, metavar="M", help="probe position when the run has no probe_x_m")
    predict.add_argument(
        "--error", metavar="COLUMN", help="thermal-error column at the probe in µm, or mm, nm by its name, or COLUMN*K"
    )
    predict.add_argument(
        "--at", metavar="X,Y,…", help="also predict the rise and the error at these positions (m from the source)"
    )
    _output_options(predict, "write the prediction as JSON", "folder for the figures")
    predict.set_defaults(handler=run_predict)

    compare = sub.add_parser("compare", help="screw model vs MLR on the same sensors, on runs not used to identify")
    compare.add_argument("run", metavar="RUN", help="identification run")
    compare.add_argument("--validate", nargs="+", required=True, metavar="CSV", help="runs of other sources")
    compare.add_argument(
        "--error", metavar="COLUMN", help="thermal-error column of every run, in µm, or mm, nm by its name, or COLUMN*K"
    )
    _model_options(compare)
    _output_options(
        compare, "write the result as JSON", f"folder for the figures and the model (default {DEFAULT_OUT})"
    )
    compare.set_defaults(handler=run_compare)


def _output_options(parser, json_help: str, out_help: str) -> None:
    """``--json`` (``json_help``, then ``('-' for stdout)``), ``--out``, ``--force``, ``--quiet`` (accepted as by
    every verb; the screw verbs show no progress bar) and the clock options."""
    parser.add_argument("--json", metavar="FILE", help=f"{json_help} ('-' for stdout)")
    parser.add_argument("--out", metavar="DIR", help=out_help)
    common.add_force_option(parser)
    common.add_quiet_option(parser)
    common.add_clock_options(parser)
    common.add_range_options(parser)


def _model_options(parser) -> None:
    parser.add_argument(
        "--alpha-law",
        choices=("table", "line"),
        default="table",
        help="how α′ is predicted: the α′(t) table identified on the first run (default), or the paper's "
        "straight line a0 + a1·τ0 in the rise at the source",
    )
    parser.add_argument("--diameter", type=float, default=0.02, metavar="M", help="screw diameter 2R0 (default 0.02)")
    parser.add_argument("--conductivity", type=float, default=45.0, metavar="W_MK", help="k (default 45)")
    parser.add_argument("--expansion", type=float, default=11.5e-6, metavar="1_K", help="a_m (default 11.5e-6)")
    parser.add_argument(
        "--offset",
        default="fit",
        metavar="M|fit",
        help="source offset x0 in m, or 'fit' (default); 0 is the paper's formula as printed",
    )
    parser.add_argument(
        "--transient-fraction",
        type=float,
        default=0.8,
        metavar="F",
        help="α′(t) enters the linear fit while τ0 < F × its steady value (default 0.8)",
    )
    parser.add_argument("--tr", type=float, default=400.0, metavar="S", help="t_r for new sources (default 400 s)")


PHYSICAL_OPTIONS = (
    ("--diameter", "diameter", 1.0, "the screw's diameter in m (20 mm is 0.02)"),
    ("--conductivity", "conductivity", 1000.0, "the thermal conductivity in W/(m·K) (steel 45)"),
    ("--expansion", "expansion", 1e-3, "the expansion coefficient in 1/K (steel 11.5e-6)"),
    ("--tr", "tr", 1e7, "t_r in s"),
)
"""(option, attribute, largest plausible value, what it is): each must be finite, positive and at most that."""


def build_model(args: argparse.Namespace):
    if args.offset == "fit":
        offset: str | float = "fit"
    else:
        try:
            offset = float(args.offset)
        except ValueError:
            raise InputError(f"--offset {args.offset!r}: give a distance in metres or 'fit'") from None
        if not 0 <= offset < 1:
            raise InputError(f"--offset {offset:g}: must be between 0 and 1 m")
    for name, value, largest, what in PHYSICAL_OPTIONS:
        value = getattr(args, value)
        if not 0 < value <= largest:
            raise InputError(f"{name} {value:g}: {what} must be positive and at most {largest:g}")
    if not 0 < args.transient_fraction < 1:
        raise InputError(f"--transient-fraction {args.transient_fraction:g}: must be between 0 and 1")
    return BallScrewModel(
        alpha_law=args.alpha_law,
        diameter=args.diameter,
        conductivity=args.conductivity,
        expansion=args.expansion,
        source_offset=offset,
        transient_fraction=args.transient_fraction,
        identification_time_s=args.tr,
    )


def identify_runs(model, runs):
    """Fit on the first run, re-identify C1, C2 on the others (all in memory)."""
    first, *others = runs
    model.fit(first.rises, first.time, first.positions, source=first.name, label=first.source)
    for run in others:
        model.fit_source(run.rises, run.time, run.positions, source=run.name, label=run.source)
    return model


def _load_runs(args: argparse.Namespace, paths, **options):
    """The screw runs ``paths``, read with the clock options of ``args``; what loading did printed as notes."""
    refuse_repeated(paths, "as screw runs")
    runs = [load_screw_run(p, **common.clock_options(args), **common.range_options(args), **options) for p in paths]
    common.print_notes([run.run for run in runs], common.report_stream(args))
    for run in runs:
        refuse_moving_source(run)
    names = [r.name for r in runs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"two runs are named '{dup[0]}' (the file stem names the source); rename one")
    return runs


def refuse_moving_source(run) -> None:
    """The seed's model covers one heat source at a fixed place; a moving nut is not that."""
    if "nut_x_m" in run.run.frame.columns:
        raise InputError(
            f"{run.source}: the heat source moves (column nut_x_m); the ball-screw model of seed 003 covers "
            "one source at a fixed place (x measured from it)"
        )


# ----------------------------------------------------------------- identify
def run_identify(args: argparse.Namespace) -> int:
    out_dir = common.plan_outputs(
        args, args.runs, folder=args.out or DEFAULT_OUT, files=("screw_model.json",), json_model=SCREW_MODELS
    )
    model = build_model(args)
    runs = _load_runs(args, args.runs)
    identify_runs(model, runs)
    data = model_to_dict(model, runs={r.name: r.source for r in runs})
    path = out_dir / "screw_model.json"
    save_model(data, path)
    common.write_json(args.json, data)
    common.commit_outputs()
    print(identify_report(model, path), file=common.report_stream(args))
    return 0


def identify_report(model, path) -> str:
    a0, a1 = model.alpha_prime_
    ident = model.identification_
    lines = [
        f"h = {model.h_:.3f} W/(m²·K)  (λ = {model.lambda_:.4f} 1/m; steady-profile residual "
        f"{ident['steady_rms_K']:.3g} K rms)",
        f"α′ = {a0 * 1e5:.3f} + {a1 * 1e5:.4f}·τ0  (10⁻⁵ m²/s; τ0 the rise at x = {1000 * model.reference_x_:g} mm; "
        f"transient residual {ident['transient_rms_K']:.3g} K rms)",
        f"source offset x0 = {1000 * model.source_offset_:.1f} mm",
        f"α′ predicted by {_law_text(model)}",
        "α′(t) as the paper's Table 1 (t ks: α′ 10⁻⁵ m²/s, τ0 K; * = in the linear fit): " + _alpha_rows(model),
        "source            C1        C2   from",
    ]
    for name, entry in model.sources_.items():
        lines.append(f"{name:<14}{entry['C1']:>8.3f}  {entry['C2']:>8.3f}   {entry['method']}")
    lines.append(f"wrote   {path}")
    return "\n".join(lines)


def _law_text(model) -> str:
    if model.alpha_law == "line":
        return "the straight line in τ0 (the paper's law; --alpha-law line)"
    times, _ = model.alpha_curve_
    return (
        f"the α′(t) table ({len(times)} times, {times[0]:g} to {times[-1]:g} s, interpolated in log t; "
        "--alpha-law table): τ0 not needed"
    )


def _alpha_rows(model) -> str:
    wanted = (100.0, 500.0, 1000.0, 1500.0, 2000.0, 3000.0, 4000.0, 5000.0, 7000.0)
    rows = [r for r in model.alpha_table_ if any(abs(r["t_s"] - t) < 1e-6 for t in wanted)]
    return "; ".join(
        f"{r['t_s'] / 1000:g}: {r['alpha_prime_m2_s'] * 1e5:.3g}, {r['tau0_K']:.1f}{'*' if r['used'] else ''}"
        for r in rows
    )


# ------------------------------------------------------------------ predict
def run_predict(args: argparse.Namespace) -> int:
    stem = Path(args.data).stem
    out_dir = common.plan_outputs(
        args,
        args.model,
        args.data,
        folder=args.out,
        files=(f"screw_rises_{stem}.png", f"screw_error_{stem}.png"),
    )
    model = load_model(args.model)
    (run,) = _load_runs(args, [args.data], probe_x=args.probe_x, error=args.error)
    source = args.source
    if source is not None and source not in model.sources_:
        raise InputError(f"--source {source}: not in {args.model}; it has {', '.join(model.sources_)}")
    reidentified = False
    if source is None:
        source = run.name
        if source not in model.sources_:
            model.fit_source(run.rises, run.time, run.positions, source=source, label=run.source)
            reidentified = True
    at = _positions(args.at, reach=probe_reach_m(run.positions))
    score, rises, error = score_screw(model, run, source)
    written = []
    if out_dir is not None:
        written = _figures(out_dir, run, rises, {"screw model": error}, f"{run.name}: source {source}")
    result = {
        "run": run.name,
        "source": source,
        "C1": model.sources_[source]["C1"],
        "C2": model.sources_[source]["C2"],
        "reidentified": reidentified,
        "metrics": score.as_dict(),
        "paper": paper_bounds(run),
        "time_s": run.time.tolist(),
        "positions_m": run.positions.tolist(),
        "sensors": list(run.names),
        "measured_rise_K": run.rises.tolist(),
        "predicted_rise_K": rises.tolist(),
        "probe_x_m": None if run.probe_x is None else run.probe_x.tolist(),
        "measured_error_um": None if run.error is None else run.error.tolist(),
        "predicted_error_um": None if error is None else error.tolist(),
        "notes": paper_notes(run),
    }
    if at is not None:
        tau0 = model.law_input(run.rises, run.positions, run.source)
        result["field"] = {
            "x_m": at.tolist(),
            "rise_K": model.predict(run.time, at, tau0, source).tolist(),
            "error_um": np.column_stack([model.predict_error(run.time, x, tau0, source) for x in at]).tolist(),
        }
    written.append(common.write_json(args.json, _finite(result)))
    common.commit_outputs()
    print(predict_report(score, run, source, reidentified, model, written), file=common.report_stream(args))
    return 0


def _positions(text: str | None, *, reach: float):
    """``--at X,Y,…`` (m from the source), each on the screw: 0 up to ``reach``, as a probe position must be."""
    if text is None:
        return None
    try:
        values = np.array([float(v) for v in text.split(",") if v.strip()])
    except ValueError:
        raise InputError(f"--at {text!r}: give positions in metres, comma separated") from None
    if not values.size or np.any(values < 0) or not np.all(np.isfinite(values)):
        raise InputError(f"--at {text!r}: give non-negative positions in metres, comma separated")
    if np.any(values > reach):
        raise InputError(
            f"--at {text!r}: {values[values > reach][0]:g} m is off the screw (x from the source, 0…{reach:g} m: "
            "twice the furthest sensor, as for a probe)"
        )
    return values


def predict_report(score, run, source, reidentified, model, written) -> str:
    entry = model.sources_[source]
    how = f"re-identified from the first {model.identification_time_s:g} s" if reidentified else "from the model"
    lines = [f"source {source}: C1 = {entry['C1']:.3f}, C2 = {entry['C2']:.3f} ({how})", _score_line(score, run)]
    lines += [f"note    {note}" for note in paper_notes(run)]
    if any(written):
        lines.append("wrote   " + common.wrote_line(written))
    return "\n".join(lines)


def _score_line(score, run) -> str:
    paper = score.paper
    if np.isfinite(score.max_um):
        at_probe = f"max error at the probe {score.max_um:.2f} µm"
    elif run.probe_x is None:
        at_probe = f"no error at the probe (the run has no '{PROBE_COLUMN}' column; or give --probe-x M)"
    else:
        at_probe = "no measured error at the probe to score (the run has no 'error_um' column; name it with --error)"
    text = (
        f"max temperature error ({paper_label(run)}) {score.max_temp_K:.2f} K (after t_r "
        f"{score.max_temp_after_tr_K:.2f} K, all sensors {score.max_temp_all_K:.2f} K); {at_probe}"
    )
    if paper:
        text += (
            f"; paper {paper['max_temp_K']} °C / {paper['max_um']} µm, scaled ×{paper['scale']:.2f} "
            f"(by {paper['rise_sensor']}): {paper['max_temp_K_scaled']:.2f} K / {paper['max_um_scaled']:.2f} µm"
        )
    return text


def _figures(out_dir: Path, run, rises, errors: dict, title: str) -> list[Path]:
    cols = paper_columns(run)[:4]
    rise_path = out_dir / f"screw_rises_{run.name}.png"
    plot_rises(run.time, run.positions[cols], run.rises[:, cols], rises[:, cols], rise_path, title)
    written = [rise_path]
    if run.error is not None and all(v is not None for v in errors.values()):
        error_path = out_dir / f"screw_error_{run.name}.png"
        plot_error(run.time, run.error, errors, error_path, title)
        written.append(error_path)
    return written


# ------------------------------------------------------------------ compare
def run_compare(args: argparse.Namespace) -> int:
    names = [Path(p).stem for p in [args.run, *args.validate]]
    out_dir = common.plan_outputs(
        args,
        args.run,
        args.validate,
        folder=args.out or DEFAULT_OUT,
        files=["screw_model.json", *(f"screw_{kind}_{n}.png" for n in names for kind in ("rises", "error"))],
    )
    keep_identified_model(out_dir / "screw_model.json", [args.run, *args.validate], force=args.force)
    model = build_model(args)
    runs = _load_runs(args, [args.run, *args.validate], require_error=True, error=args.error)
    for run in runs:
        if run.probe_x is None:
            raise InputError(f"{run.source}: no probe_x_m column; the probe position is needed to score the error")
    result = compare_screw(model, runs[0], runs[1:])
    written = []
    for run in runs:
        pred = result.predictions[run.name]
        role = "identification" if run is runs[0] else "validation"
        written += _figures(
            out_dir,
            run,
            pred["rises"],
            {"screw model": pred["error"], "MLR (same sensors)": pred["mlr"]},
            f"{run.name} ({role})",
        )
    model_path = out_dir / "screw_model.json"
    save_model(model_to_dict(model, runs={r.name: r.source for r in runs}), model_path)
    written.append(model_path)
    common.write_json(args.json, _finite(compare_json(result, runs)))
    common.commit_outputs()
    print(compare_report(result, runs, written), file=common.report_stream(args))
    return 0


def keep_identified_model(path: Path, sources, *, force: bool) -> None:
    """Refuse, without ``--force``, to replace a ball-screw model file identified from other runs than ``sources``.

    ``screw identify`` and ``screw compare`` both write ``screw_model.json`` into
    their ``--out`` folder; a model identified from other runs (or from the
    same runs in another order: the first names the source identified in
    full) may be the only copy of one in use. A file that is no ball-screw
    model is the verb's own output, replaced as before.
    """
    if force or not path.is_file():
        return
    try:
        existing = json.loads(path.read_text(encoding="utf-8"))
        identified = existing["identification"]["runs"].values()
    except (OSError, UnicodeDecodeError, ValueError, TypeError, KeyError, AttributeError):
        return
    if not str(existing.get("format", "")).startswith(SCREW_MODELS):
        return
    if [resolved_path(str(s)) for s in identified] != [resolved_path(s) for s in sources]:
        names = ", ".join(sorted(Path(str(s)).name for s in identified))
        raise InputError(
            f"{path}: --out holds a ball-screw model identified from other runs ({names}); screw compare would "
            "replace it: choose another --out, or pass --force to replace it"
        )


def compare_json(result, runs) -> dict[str, Any]:
    a0, a1 = result.model.alpha_prime_
    return {
        "runs": [r.name for r in runs],
        "rows": [s.as_dict() for s in result.scores],
        "h_W_m2K": result.model.h_,
        "alpha_prime": {"used": result.model.alpha_law, "a0_m2_s": a0, "a1_m2_sK": a1},
        "source_offset_m": result.model.source_offset_,
        "sources": [{"name": n, **e} for n, e in result.model.sources_.items()],
    }


def compare_report(result, runs, written) -> str:
    model = result.model
    header = (
        f"{'run':<12}{'role':<15}{'C1':>7}{'C2':>7}  {'screw: max ΔT':>13}{'after t_r':>10}{'max|e|':>8}{'RMS':>7}"
        f"  {'MLR: max|e|':>11}{'RMS':>7}  {'paper (scaled) ΔT / e':>22}"
    )
    lines = [header]
    index = {(s.model, s.run): s for s in result.scores}
    for i, run in enumerate(runs):
        screw, mlr = index[("screw", run.name)], index[("mlr", run.name)]
        entry = model.sources_[run.name]
        paper = screw.paper
        paper_text = f"{paper['max_temp_K_scaled']:.2f} K / {paper['max_um_scaled']:.2f} µm" if paper else "-"
        lines.append(
            f"{run.name:<12}{'identification' if i == 0 else 'validation':<15}{entry['C1']:>7.2f}{entry['C2']:>7.2f}"
            f"  {screw.max_temp_K:>11.2f} K{screw.max_temp_after_tr_K:>8.2f} K{screw.max_um:>8.2f}{screw.rms_um:>7.2f}"
            f"  {mlr.max_um:>11.2f}{mlr.rms_um:>7.2f}  {paper_text:>22}"
        )
    a0, a1 = model.alpha_prime_
    lines += [
        "",
        f"h = {model.h_:.3f} W/(m²·K) (paper {17.2}); α′ = {a0 * 1e5:.3f} + {a1 * 1e5:.4f}·τ0 (10⁻⁵ m²/s; "
        f"paper 0.6 + 0.08·τ0); x0 = {1000 * model.source_offset_:.1f} mm; α′ predicted by {_law_text(model)}",
        "max ΔT over the sensors at 0, 4, 8, 12 cm and the whole run (after t_r: from t_r on); errors in µm at the "
        "probe; the MLR maps the same sensors to the error, fitted on the identification run",
        "wrote   " + ", ".join(str(p) for p in written),
    ]
    return "\n".join(lines)


def _finite(obj):
    """NaN → None, so that the JSON stays strict."""
    if isinstance(obj, float):
        return obj if np.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite(v) for v in obj]
    return obj
