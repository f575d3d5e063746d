"""How near the filter ``--recalibrate auto`` chooses comes to the best of its own grid on the next run.

Usage::

    python bench/bench_recalibration_choice.py [--diagnose] [--every 30m,60m] [--only NAME ...] [--json FILE]

The pairs are those of ``bench/bench_probe_pairs.py`` (model run → a later run
of the same machine the model never saw). Each model is built as a user builds
it (``groupfit fit`` with its defaults; ``--diagnose``: then ``groupfit
diagnose``). Every candidate filter of the held-out tuning
(:func:`groupfit.recalibration_tuning.score_candidates`: the same grid, check
noise and gate as the choice) is then replayed on the next run's residual
(measured error − the model's prediction, from ``groupfit replay`` without
checks), with a check every T from one interval into the run on. The replay is
the tuning's own, vectorised one: from the first check on without the
compensation's clamp and rate limit (before it, every candidate serves what
``replay`` without checks serves), so its figures for the chosen filter can
differ from ``replay --probe-every`` where the clamp or the rate limit binds
(both are printed).

The chosen filter is compared, per pair and interval, with: the offset hold;
no checks; the best candidate of the grid on that very run (hindsight: what no
choice made before the run can beat); and the one candidate that does best
over the whole panel (a fixed filter for every machine). Printed overall:
geometric means of the ratios, how many pairs the chosen filter leaves worse
than the hold or than no checks by more than 5 %, and on how many pairs no
candidate of the grid is better than no checks by 5 % (a model at its noise
floor there: checks have nothing to take) and on how many every candidate is
worse than no checks by more than 5 % (where no filter of the grid could meet
"never worse than no checks").
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_probe_pairs import BuiltPair, built_pairs, replayed  # noqa: E402

from groupfit.data import load_run  # noqa: E402
from groupfit.model import ModelFile  # noqa: E402
from groupfit.probe_intervals import parse_intervals, whole_samples  # noqa: E402
from groupfit.recalibration_candidates import HeldOut, replay_candidates  # noqa: E402
from groupfit.recalibration_tuning import score_candidates  # noqa: E402

TOLERANCE = 1.05
"""Worse by more than 5 %: the issue's tolerance against the hold, used against no checks as well."""
SECTION_KEYS = ("terms", "offset_sigma_um_per_sqrt_h", "drift_sigma_um_per_h_per_sqrt_h", "drift_tau_h")


def next_run_rms(scores, served: np.ndarray, measured: np.ndarray, prediction: np.ndarray, every: int, period_s: float):
    """RMS over the next run of every candidate with a check every ``every`` samples. Before the first check every
    candidate serves what ``replay`` without checks serves (``served``: its residual, the clamp and rate limit
    counted); from the first check on, the model's prediction corrected by the candidate."""
    residual = measured - prediction
    total, n = replay_candidates(HeldOut(residual, prediction), scores.candidates, every=every, period_s=period_s)
    head = served[:every]
    head = head[np.isfinite(head)]
    return np.sqrt((total + np.sum(head**2)) / (n + head.size))


def matches_file(scores, model: ModelFile) -> bool:
    """Whether the candidate the tuning keeps here is the filter in the model file (same terms and noise)."""
    section = model.recalibration
    if section is None or scores.candidates is None:
        return False
    kept = scores.candidates.section(scores.chosen, offset_max_um=1.0, rate_um=1.0, chosen={})
    return all(np.all(np.asarray(getattr(kept, k)) == np.asarray(getattr(section, k))) for k in SECTION_KEYS)


def describe(candidates, k: int) -> str:
    """One candidate in a few words: its terms and how fast each wanders."""
    c = candidates
    if c.probe_sigma[k] == 0:
        return "offset hold"
    words = [f"offset {c.offset_sigma[k]:g} µm/√h"]
    if "drift" in c.terms[k]:
        words.append(f"drift {c.drift_sigma[k]:g} µm/h/√h τ {c.drift_tau_h[k]:g} h")
    if "gain" in c.terms[k]:
        words.append(f"gain {c.gain_sigma[k]:g}/√h from ±{c.initial_gain[k]:g}")
    return "Kalman " + ", ".join(words)


def pair_result(pair: BuiltPair, intervals_s) -> dict:
    model = ModelFile.load(pair.model_path)
    run = load_run(pair.folder / "model_run.csv", temps=pair.temps, error=pair.error)
    scores = score_candidates(model, [(run.frame, run.error)])
    if scores.reason or scores.candidates is None:
        return {"pair": pair.name, "source": pair.source, "skipped": scores.reason or "no candidates"}
    unchecked = replayed(pair.folder, pair.model_path, pair.next_path)
    samples = unchecked["samples"]
    prediction = np.array([s["prediction_um"] for s in samples], dtype=float)
    residual = np.array([np.nan if s["residual_um"] is None else s["residual_um"] for s in samples], dtype=float)
    measured = residual - np.array([s["compensation_um"] for s in samples], dtype=float)
    period = float(model.sampling_period_s)
    per_interval = []
    for t in intervals_s:
        rms = next_run_rms(scores, residual, measured, prediction, whole_samples(t, period), period)
        cli = replayed(pair.folder, pair.model_path, pair.next_path, "--probe-every", f"{t:g}")["rms_um"]
        per_interval.append({"candidates": rms.tolist(), "chosen": float(rms[scores.chosen]), "replay_chosen": cli})
    return {
        "pair": pair.name,
        "source": pair.source,
        "none": float(unchecked["rms_um"]),
        "chosen_index": int(scores.chosen),
        "chosen": model.recalibration.description if model.recalibration else "none",
        "matches_file": matches_file(scores, model),
        "descriptions": [describe(scores.candidates, k) for k in range(len(scores.candidates))],
        "intervals": per_interval,
    }


def report(results: list[dict], intervals_s) -> str:
    scored = [r for r in results if "skipped" not in r]
    lines = [
        f"{'pair':<48}{'none':>8}" + "".join(f"{f'{t / 60:g} min: hold/chosen (replay)/best':>36}" for t in intervals_s)
    ]
    for r in scored:
        cells = ""
        for cell in r["intervals"]:
            rms, chosen, cli = cell["candidates"], cell["chosen"], cell["replay_chosen"]
            cells += f"{f'{rms[0]:.3g} / {chosen:.3g} ({cli:.3g}) / {min(rms):.3g}':>36}"
        flag = "" if r["matches_file"] else "  (the file's filter differs)"
        lines.append(f"{r['pair'][:47]:<48}{r['none']:>8.3g}{cells}{flag}")
    lines += [f"skipped {r['pair']}: {r['skipped']}" for r in results if "skipped" in r]
    lines += [summary(scored, k, t) for k, t in enumerate(intervals_s)]
    return "\n".join(lines)


def summary(results: list[dict], k: int, interval_s: float) -> str:
    """Ratios of the chosen, the hindsight best and the best fixed candidate to the hold and to no checks."""
    rms = np.array([r["intervals"][k]["candidates"] for r in results])
    none = np.array([r["none"] for r in results])
    chosen = np.array([r["intervals"][k]["chosen"] for r in results])
    hold = rms[:, 0]
    fixed = int(np.argmin(np.mean(np.log(rms / hold[:, None]), axis=0)))
    best = rms.min(axis=1)

    def geo(values):
        return float(np.exp(np.mean(np.log(values))))

    return (
        f"every {interval_s / 60:g} min, {len(results)} pairs: to the hold (geometric mean) chosen "
        f"{geo(chosen / hold):.3f}, best fixed candidate ({results[0]['descriptions'][fixed]}) "
        f"{geo(rms[:, fixed] / hold):.3f}, hindsight best {geo(best / hold):.3f}; "
        f"chosen worse than the hold by > 5 %: {int(np.sum(chosen > TOLERANCE * hold))}, than no checks: "
        f"{int(np.sum(chosen > TOLERANCE * none))}; no candidate better than no checks by 5 %: "
        f"{int(np.sum(best > none / TOLERANCE))}, every candidate worse than no checks by > 5 %: "
        f"{int(np.sum(best > TOLERANCE * none))}; files matched: {sum(r['matches_file'] for r in results)}"
    )


def run(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results here")
    parser.add_argument("--every", default="30m,60m", help="check intervals (default 30m,60m)")
    parser.add_argument("--diagnose", action="store_true", help="run groupfit diagnose on the model run too")
    parser.add_argument("--only", nargs="+", help="pair names")
    args = parser.parse_args(argv)
    intervals = parse_intervals(args.every)
    started = time.perf_counter()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for pair in built_pairs(Path(tmp), only=args.only, diagnose=args.diagnose):
            results.append(pair_result(pair, intervals))
            print(f"{pair.name}: done", flush=True)
    print(report(results, intervals))
    print(f"{len(results)} pair(s) in {time.perf_counter() - started:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(run())
