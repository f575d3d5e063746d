"""The calibration panel of the next-run estimate: pairs of runs (model run → next run) and what happened on them.

Every pair is a model run and a later run of the same machine that the model
never saw. For each pair :func:`score_pair` computes, from the model run alone,
the raw next-run figure of every p = 0…3 (:func:`groupfit.heldout.nextrun.forward_chaining`)
and the p it chooses; then it fits every p on the whole model run as ``groupfit
fit`` does (the exact optimum of the configured objective Σ|e|, groups by least
squares), replays each through the run-time rule over the next run and records
the actual RMS, the choice of BIC over p = 0…3 and the best p.

Sources (:func:`panel_pairs`): the independent lumped machine
(``independent_machine.py``: random machines, schedules and workshop days), the
finite-element repeats and other-condition runs in ``datasets/``, and the
diagnosis data sets' model → validate pairs. :func:`measured_pairs` cuts the
shared measured test (``../shared``) into runs; they join the calibration (the
only real runs of the panel); a cut that is the rest of the model run's recording is
replayed with the model run in front, as ``groupfit replay`` does.
"""

from __future__ import annotations

import dataclasses
import itertools
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from groupfit.columns import usable_columns
from groupfit.data import Run, join_runs, load_run
from groupfit.heldout import calibration
from groupfit.heldout.expect import expect_next_run
from groupfit.heldout.folds import operating_columns
from groupfit.heldout.nextrun import rule_prediction, sliced
from groupfit.heldout.penalty import run_penalty
from groupfit.heldout.reference_choice import choose_reference
from groupfit.heldout.span import REFERENCE_TOLERANCE, beyond_span, input_span, reference_span
from groupfit.models.grouped import GroupedRegressor
from groupfit.models.select_p import choose_p, exact_path
from groupfit.reference import default_reference, is_column_reference, with_reference

sys.path.insert(0, str(Path(__file__).resolve().parent))
import independent_machine as machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATASETS = ROOT / "datasets"
MEASURED = ROOT.parent / "shared" / "data" / "fl_thermal" / "spindle_step_test.csv"
"""The shared measured test, next to the project (``../shared``); its cuts are left out when it is absent."""
P_VALUES = (0, 1, 2, 3)
DEFAULT_P = 3
"""The default ``fit`` before the next-run choice."""
MAX_SAMPLES = 600
"""Both runs of a pair are thinned by the stride that brings the model run to at most this many samples."""
SETTINGS = {"n": 3, "c": 3.0, "fit_intercept": True}

FE_PAIRS = [
    ("paper_cycle", "repeat_timing"),
    ("paper_cycle", "repeat_ambient25"),
    ("paper_cycle", "repeat_warm"),
    ("paper_cycle", "validation_speed"),
    ("paper_cycle", "validation_timing"),
    ("repeat_timing", "paper_cycle"),
    ("repeat_ambient25", "repeat_warm"),
    ("validation_speed", "paper_cycle"),
    ("validation_timing", "repeat_timing"),
]
DIAG_KINDS = ("none", "ambient", "lag", "source", "speed")


@dataclass
class Pair:
    name: str
    source: str
    model: Run
    next: Run
    continues: bool = False
    """The next run is the rest of the model run's recording: replayed with the model run in front (as
    ``groupfit replay`` replays a file whose clock runs on from the modelling file)."""
    reference: str | None = None
    """The default reference of ``fit`` (the ambient column when the run has one); the runs are kept as read."""


def thin_pair(model: Run, next_run: Run, max_samples: int = MAX_SAMPLES) -> tuple[Run, Run]:
    """Both runs with every k-th row, k bringing the model run to at most ``max_samples`` rows."""
    stride = max(1, int(np.ceil(model.n_samples / max_samples)))
    if stride == 1:
        return model, next_run
    return (
        sliced(model, np.arange(0, model.n_samples, stride), period=model.period * stride),
        sliced(next_run, np.arange(0, next_run.n_samples, stride), period=next_run.period * stride),
    )


def frame_run(frame: pd.DataFrame, name: str, temps, error: str = "error_um", time: str = "time_s") -> Run:
    return load_run(frame, name=name, temps=list(temps), time=time, error=error)


def make_pair(
    name: str, source: str, model: Run, next_run: Run, reference: str | None = "default", *, continues: bool = False
) -> Pair:
    if reference == "default":
        reference = default_reference(model.frame)
    model, next_run = thin_pair(model, next_run)
    return Pair(name, source, model, next_run, continues, reference)


def fe_pairs() -> list[Pair]:
    out = []
    for a, b in FE_PAIRS:
        runs = [load_run(DATASETS / f"{x}.csv", temps=["T1", "T2"]) for x in (a, b)]
        out.append(make_pair(f"{a}→{b}", "FE", *runs))
    for kind in DIAG_KINDS:
        runs = [load_run(DATASETS / f"diag_{kind}_{x}.csv", temps=["T1", "T2"]) for x in ("model", "validate")]
        out.append(make_pair(f"diag_{kind}", "FE diag", *runs))
    return out


def simulator_scenarios(seeds=range(14), rises_seeds=range(100, 106)):
    """``(pair name, scenario)`` of the independent machine's pairs: its error over 20 °C (``seeds``) and over
    the air (``rises_seeds``, named ``…_rises``)."""
    for truth, seed_range in (("absolute", seeds), ("rises", rises_seeds)):
        for seed in seed_range:
            scenario = machine.random_spec(seed, truth).make()
            yield f"{scenario.name}{'_rises' if truth == 'rises' else ''}", scenario


def simulator_pairs(seeds=range(14), rises_seeds=range(100, 106)) -> list[Pair]:
    out = []
    for name, scenario in simulator_scenarios(seeds, rises_seeds):
        model = frame_run(scenario.modelling, f"{scenario.name}_model", scenario.temps)
        next_run = frame_run(scenario.validation, f"{scenario.name}_next", scenario.temps)
        out.append(make_pair(name, "simulator", model, next_run))
    return out


MEASURED_SENSORS = [f"t{k}_C" for k in range(1, 17)]
MEASURED_CUTS = {
    "first 60 % → rest": ((0.0, 0.6), (0.6, 1.0)),
    "first half → second half": ((0.0, 0.5), (0.5, 1.0)),
    "second half → first half": ((0.5, 1.0), (0.0, 0.5)),
    "1250-2500 r/min blocks → 3750 r/min block": ((0.0, 0.6), (0.6, 0.83)),
    "first 40 % → next 30 %": ((0.0, 0.4), (0.4, 0.7)),
}


def measured_cuts(n_samples: int):
    """``(name, model rows, next rows, continues)`` of every cut of the measured test's ``n_samples`` rows."""
    for name, ((a0, a1), (b0, b1)) in MEASURED_CUTS.items():
        yield (
            name,
            slice(int(a0 * n_samples), int(a1 * n_samples)),
            slice(int(b0 * n_samples), int(b1 * n_samples)),
            (b0 == a1),
        )


def measured_pairs() -> list[Pair]:
    """Cuts of the shared measured test into model and next runs; empty when ``../shared`` is absent."""
    if not MEASURED.exists():
        return []
    whole = load_run(MEASURED, temps=MEASURED_SENSORS, error="disp_ch3_um")
    return [
        make_pair(name, "measured", sliced(whole, model), sliced(whole, following), reference=None, continues=joined)
        for name, model, following, joined in measured_cuts(whole.n_samples)
    ]


def without_operating_columns(pair: Pair) -> Pair:
    """The pair as a log without its operating columns (no speed, no on/off of a source) would give it: the
    estimate then cuts the model run into blocks of time (:mod:`groupfit.heldout.folds`)."""
    run = pair.model
    columns, _ = usable_columns(run.frame, {run.time_name, run.error_name, *run.temp_names})
    settings = operating_columns(run.frame, columns)
    model = dataclasses.replace(run, frame=run.frame.drop(columns=settings))
    return dataclasses.replace(pair, model=model)


def score_pair(pair: Pair) -> dict:
    """The estimate, the actual next-run RMS of every p, and the choices of the estimate, BIC and the default.

    The reference is decided as ``fit`` decides it when none is configured
    (:func:`groupfit.heldout.reference_choice.choose_reference`); BIC and the
    old default p = 3 keep the default reference, as ``fit`` did before. The
    best is the least actual RMS over p = 0…3 and both references.
    """
    default = pair.reference
    choice = None
    chosen_reference = default
    if is_column_reference(default):
        choice = choose_reference([pair.model], default, P_VALUES, **SETTINGS)
        chosen_reference = choice.reference
    if choice is not None and choice.scored:
        expectation = choice.expectations[chosen_reference]
    else:
        expectation = expect_next_run([with_reference(pair.model, chosen_reference)], P_VALUES, **SETTINGS)
    actual_default, bic_p, n_model = actual_by_p(pair, default)
    actual = actual_default if chosen_reference == default else actual_by_p(pair, chosen_reference)[0]
    chosen = expectation.candidates[expectation.chosen]
    raw = float(expectation.scores.raw_rms()[expectation.chosen])
    best = min(*actual.values(), *actual_default.values())
    default_p = min(DEFAULT_P, max(actual_default))
    model = with_reference(pair.model, chosen_reference)
    alpha, actual_chosen = 0.0, actual[chosen]
    if chosen == 0:  # fit gives the global model the penalty with the least error on held-out conditions
        alpha = run_penalty(model).alpha
        if alpha > 0:
            raw = float(expect_next_run([model], (0,), **SETTINGS, ridge_alpha=alpha).scores.raw_rms()[0])
            actual_chosen = actual_by_p(pair, chosen_reference, ridge_alpha=alpha, p_values=(0,))[0][0]
    return {
        "pair": pair.name,
        "source": pair.source,
        "reference": chosen_reference,
        "default_reference": default,
        "reference_choice": None if choice is None else choice.to_json(),
        "chosen_p": chosen,
        "ridge_alpha": alpha,
        "raw_um": raw,
        "actual_um": actual_chosen,
        "actual_least_squares_um": actual[chosen],
        "actual_by_p": actual,
        "actual_by_p_default_reference": actual_default,
        "best_p": min(actual, key=actual.get),
        "bic_p": bic_p,
        "within_chosen": actual_chosen <= 1.5 * best,
        "within_bic": actual_default[bic_p] <= 1.5 * best,
        "within_default": actual_default[default_p] <= 1.5 * best,
        "notes": list(expectation.notes),
        "error_sd_um": float(np.std(model.error)),
        "next_error_sd_um": float(np.std(pair.next.error)),
        "raw_by_p": dict(zip(expectation.candidates, map(float, expectation.scores.raw_rms()))),
        "n_folds": expectation.scores.n_folds,
        "unseen_condition": expectation.scores.unseen_condition,
        "inputs_beyond_span": inputs_beyond_span(model, with_reference(pair.next, chosen_reference)),
        "n_model": n_model,
        "n_next": pair.next.n_samples,
    }


def expected_um(row: dict, factor: float | None = None) -> float:
    """The pair's expected next-run RMS: its raw figure times ``factor`` (default: the shipped
    :data:`~groupfit.heldout.calibration.FACTOR`), or times the factor of a run whose scored segments start a
    condition the run before them never saw (:data:`~groupfit.heldout.calibration.UNSEEN_CONDITION_FACTOR`)."""
    if row.get("unseen_condition"):
        return calibration.UNSEEN_CONDITION_FACTOR * row["raw_um"]
    return (calibration.FACTOR if factor is None else factor) * row["raw_um"]


def inputs_beyond_span(model: Run, next_run: Run) -> list[str]:
    """The inputs the next run takes beyond the model run's span, as ``groupfit replay`` checks them
    (:mod:`groupfit.heldout.span`): where it notes that the expected figure does not cover the run."""
    names = list(model.temp_names)
    beyond = beyond_span(input_span(names, model.temps), names, next_run.temps)
    reference = reference_span([model.frame], model.reference, names)  # a day at another air level
    for name in reference:
        if name in next_run.frame.columns:
            readings = next_run.frame[name].to_numpy(dtype=float)[:, None]
            beyond += beyond_span(reference, [name], readings, REFERENCE_TOLERANCE)
    return [entry["input"] for entry in beyond]


def actual_by_p(
    pair: Pair, reference: str | None, *, ridge_alpha: float = 0.0, p_values=P_VALUES
) -> tuple[dict, int, int]:
    """Every p fitted on the model run as ``fit`` fits it (inputs relative to ``reference``; the global model with
    the penalty ``ridge_alpha``) and replayed through the run-time rule over the next run: the actual RMS per p,
    BIC's p and the model run's samples."""
    model, next_run = with_reference(pair.model, reference), with_reference(pair.next, reference)
    path = exact_path(model.temps, model.error, max(p_values), objective="sae", **_path_settings())
    actual = {}
    for p in p_values:
        if p >= len(path["breaks"]):
            continue
        estimator = GroupedRegressor(
            p=p,
            n=SETTINGS["n"],
            c=SETTINGS["c"],
            fixed_breaks=path["breaks"][p] or None,
            ridge_alpha=ridge_alpha if p == 0 else 0.0,
        )
        estimator.fit(model.temps, model.error)
        if pair.continues:  # the rule runs on from the model run, as on the controller
            whole = rule_prediction(estimator, model, np.vstack([model.temps, next_run.temps]))
            prediction = whole[model.n_samples :]
        else:
            prediction = rule_prediction(estimator, model, next_run.temps)
        residual = next_run.error - prediction
        actual[p] = float(np.sqrt(np.mean(residual[np.isfinite(residual)] ** 2)))
    n_coef = model.temps.shape[1] + 1
    bic_p = choose_p(path["rss"], path["R"], model.n_samples, n_coef, "bic")["p"]
    return actual, bic_p, model.n_samples


def _path_settings() -> dict:
    return {"n": SETTINGS["n"], "c": SETTINGS["c"], "fit_intercept": SETTINGS["fit_intercept"]}


FE_RUNS = ("paper_cycle", "repeat_timing", "repeat_ambient25", "repeat_warm", "validation_speed", "validation_timing")


def several_run_rows(sizes=(2, 3)) -> list[dict]:
    """Leave-one-run-out on several FE runs → another of the six: the estimate ``fit --data A B [C]`` prints
    (not scaled), its range, and the actual RMS of the global model fitted on all of them (with the penalty fit
    gives it, least error on held-out runs or conditions)."""
    runs = {
        name: with_reference(load_run(DATASETS / f"{name}.csv", temps=["T1", "T2"], name=name), "T_amb")
        for name in FE_RUNS
    }
    rows = []
    for size in sizes:
        for names in itertools.combinations(FE_RUNS, size):
            modelling = [runs[name] for name in names]
            joined = join_runs(modelling)
            alpha = run_penalty(joined, frames=[run.frame for run in modelling]).alpha
            expected, (low, high) = expect_next_run(modelling, (0,), ridge_alpha=alpha).expected()
            estimator = GroupedRegressor(p=0, ridge_alpha=alpha).fit(joined.temps, joined.error)
            for name in FE_RUNS:
                if name in names:
                    continue
                residual = runs[name].error - rule_prediction(estimator, joined, runs[name].temps)
                actual = float(np.sqrt(np.mean(residual**2)))
                rows.append(
                    {
                        "model_runs": names,
                        "next_run": name,
                        "expected_um": expected,
                        "range_um": [low, high],
                        "actual_um": actual,
                        "ridge_alpha": alpha,
                    }
                )
    return rows


def panel_pairs() -> list[Pair]:
    return simulator_pairs() + fe_pairs()
