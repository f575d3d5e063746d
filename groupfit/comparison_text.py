"""The text ``groupfit compare`` prints: the comparison table, the breaks, the choice of p and the notes."""

from __future__ import annotations

from typing import Any

import numpy as np

from groupfit.comparison_fit import fit_model_line
from groupfit.heldout.penalty import penalty_lines
from groupfit.inference.cli import interval_notes

MODEL_LABELS = {"mlr": "MLR (p = 0)", "fit": "fit's model", "ar1": "AR(1) free run"}


def comparison_summary(result: Any) -> str:
    """The comparison table and its notes, as ``groupfit compare`` prints them (``result``: a
    :class:`groupfit.comparison.ComparisonResult`)."""
    modelling = result.runs[0]
    grouped_keys = sorted(
        {f"grouped{r['p']}" for r in result.rows if r["model"] == "grouped"}, key=lambda k: int(k[7:])
    )
    fit_key = ["fit"] if getattr(result, "fit_model", None) is not None else []
    keys = ["mlr"] + fit_key + (["ar1"] if result.ar1 is not None else []) + grouped_keys
    index = {(r["model"] if r["model"] != "grouped" else f"grouped{r['p']}", r["run"]): r for r in result.rows}
    lines = [f"note    {note}" for note in result.notes] + comparison_table(result, keys, index)
    lines += (
        []
        if not grouped_keys
        else [
            "",
            f"breaks on {modelling} (distance in samples to the nearest change of operating condition at "
            f"{result.condition_changes}):"
            if result.condition_changes
            else f"breaks on {modelling} (no change of operating condition to compare them with):",
        ]
    )
    for key in grouped_keys:
        r = index[(key, modelling)]
        report = result.break_intervals.get(r["p"])
        cis = [f" {report.text_for(b)}" if report is not None and report.intervals else "" for b in r["breaks"]]
        pairs = ", ".join(
            f"{b}{ci}" + (f" ({d})" if d is not None else "") for b, ci, d in zip(r["breaks"], cis, r["break_distance"])
        )
        lines.append(f"  p = {r['p']}: {pairs}")
    lines += interval_notes(result.break_intervals)
    stability = ", ".join(f"p {s['from_p']}→{s['to_p']}: {s['max_shift']}" for s in result.break_stability)
    if grouped_keys:
        lines.append(f"break stability (largest move of an existing break when p grows, samples): {stability or '-'}")
    bic, target = result.selection["bic"], result.selection["target"]
    lines.append(
        f"how many breaks: BIC (in sample) chooses p = {bic['p']}; the target rule (R <= {target['target_um']:.4g} µm) "
        f"chooses p = {target['p'] if target['p'] is not None else 'none up to pmax'}"
    )
    lines += result.expectation.candidate_lines(result.runs[0], result.fit_choice) if result.expectation else []
    lines += penalty_lines(result.fit_penalty)
    lines += [fit_model_line(result.fit_model)] if fit_key else []
    stats = result.mlr_statistics
    terms = ", ".join(
        f"{t['name']} {t['estimate']:.4g} ± {t['std_error']:.2g} (t = {t['t']:.1f})" for t in stats["terms"]
    )
    f_text = f"F = {stats['f_value']:.4g} (p = {stats['f_p_value']:.2g}), " if stats["f_value"] is not None else ""
    lines.append(f"MLR: {terms}; {f_text}R² = {stats['r_squared']:.5f}, σ = {stats['sigma_um']:.3g} µm")
    lines.append(ar1_line(result.ar1, left_out=result.ar1_left_out))
    lines += ar1_expectation_lines(result)
    if grouped_keys:
        lines.append(
            f"grouped models on validation runs: groups chosen by {result.validation_rule}; "
            "they are fitted to the modelling run's condition and are not retuned."
        )
    return "\n".join(lines)


def ar1_expectation_lines(result) -> list[str]:
    """The AR(1) model's expected next-run RMS, its range and notes (none when it was not estimated)."""
    expectation = result.ar1_expectation
    if expectation is None:
        return []
    value, (low, high) = expectation.expected()
    return [
        f"AR(1) expected next-run RMS from {result.runs[0]} alone: {value:.3g} µm (range {low:.3g}-{high:.3g} µm; "
        f"{expectation.scores.method()})",
        *(f"note: {note}" for note in expectation.notes),
    ]


def ar1_line(ar1: dict[str, Any] | None, left_out: str | None = None) -> str:
    """The summary line of the AR(1) model (``left_out``: why it was, if not for want of a heat column)."""
    if ar1 is None:
        return f"AR(1): left out ({left_out or 'no heat-level column; --heat COLUMN names one'})"
    c2 = ", ".join(f"C2({level}) = {value:.4g} µm" for level, value in ar1["C2"].items())
    lb = ar1["ljung_box"]
    start = (
        "free run from each run's first measured error; "
        if ar1.get("start", "measured") == "measured"
        else "free run from 0 (ΔL(0) = 0); "
    )
    return (
        f"AR(1) on {ar1['heat']}: C1 = {ar1['C1']:.5f}, {c2}; unseen levels by {ar1['scaling'].replace('_', ' ')}; "
        + start
        + ("fitted on the free-run error; " if ar1.get("fit") == "free_run" else "")
        + f"Ljung–Box Q({lb['lags']}) = {lb['Q']:.1f}, p = {lb['p_value']:.2g}"
    )


def comparison_table(result: Any, keys: list[str], index: dict) -> list[str]:
    """One line per run (its condition, then every model's RMS, R, max |e| and accuracy %), the best model named."""
    names = [
        MODEL_LABELS.get(key, f"p = {key[7:]}").replace(" (p = 0)", "").replace(" free run", "").replace(" model", "")
        for key in keys
    ]
    width = max(len(run) for run in result.runs)
    reference = result.reference or "none (absolute temperatures)"
    lines = [f"inputs relative to: {reference}"]
    tables = (("RMS µm", "rms_um", 3), ("R = Σ|e| µm", "R_um", 2), ("max |e| µm", "max_um", 3))
    tables += (("accuracy %", "accuracy_percent", 1),)  # Du et al.: 100·(1 − max|residual| / max|error|)
    for title, metric, digits in tables:
        table = [[index[(key, run)][metric] for key in keys] for run in result.runs]
        column = max([8, *(len(n) + 2 for n in names), *(len(f"{v:.{digits}f}") + 2 for row in table for v in row)])
        lines.append("")
        lines.append(f"{title:<{width}}  {'condition':<15}" + "".join(f"{n:>{column}}" for n in names) + "  best")
        for run, values in zip(result.runs, table):
            best = keys[int(np.argmax(values) if metric == "accuracy_percent" else np.argmin(values))]
            best_name = MODEL_LABELS.get(best, f"grouped p = {best[7:]}")
            condition = result.run_conditions.get(run, "")
            cells = "".join(f"{v:>{column}.{digits}f}" for v in values)
            lines.append(f"{run:<{width}}  {condition:<15}{cells}  {best_name}")
    return lines
