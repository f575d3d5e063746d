"""The diagnosis in words: what ``groupfit diagnose`` prints."""

from __future__ import annotations

from groupfit.columns import is_ambient_name
from groupfit.diagnose.notes import COLD_START, OVERFIT
from groupfit.diagnose.policy import REFERENCE_STEADY


def column_words(column: str, ambient: tuple[str, ...] = ()) -> str:
    """What a column is, in words, for the report; ``ambient``: columns declared ambient temperatures."""
    lowered = column.lower()
    if is_ambient_name(column) or column in ambient:
        return f"ambient temperature `{column}`"
    if column.startswith("src_") and column.endswith("_on"):
        return f"heat source '{column[4:-3]}' (on/off `{column}`)"
    if column == "spindle_on":
        return f"spindle heat, a part that lags it (`{column}`)"
    if "speed" in lowered or "rpm" in lowered:
        return f"spindle speed, a part that lags it (`{column}`)"
    if lowered.endswith("_on"):
        return f"heat source '{column[:-3]}' (on/off `{column}`)"
    return f"column `{column}`"


def effect_count(n: int) -> str:
    """``effect`` for one, ``2 effects`` for more: "the effect found on it", "the first 2 effects"."""
    return "effect" if n == 1 else f"{n} effects"


def change_words(before: float, after: float) -> str:
    """``RMS 11 → 4.4 µm (60 % lower)`` or ``(80 % higher)``."""
    if before <= 0:
        return f"{before:.3g} → {after:.3g} µm"
    change = 100.0 * (after - before) / before
    if abs(change) < 0.5:
        words = "unchanged"
    else:
        words = f"{abs(change):.0f} % {'higher' if change > 0 else 'lower'}"
    return f"{before:.3g} → {after:.3g} µm ({words})"


def diagnosis_summary(result) -> str:
    """What ``groupfit diagnose`` prints (without the files it wrote)."""
    validate = "validate" in result.before
    judge = "validate" if validate else "data"
    b, a = result.before[judge], result.after[judge]
    worse = result.improved is False or (validate and result.changed and a["rms_um"] >= b["rms_um"])
    overfit_in_head = not result.added and result.base_check is not None and result.base_check.overfitted
    lines = worse_lines(result, judge) if worse else []
    lines += selection_lines(result) + ridge_lines(result) + reference_lines(result)
    lines += effect_lines(result, judge) if result.added else outcome_lines(result, judge)
    lines.append(f"held out: {result.folds}")
    for refusal in result.refused[:5]:
        c = refusal.candidate
        lines.append(f"refused: {c.feature.column} {c.describe()} (score {c.score:.2f}): {refusal.reason}")
    lines += ["", *candidate_table(result.candidates[:10]), "", *metrics_lines(result), residual_line(result)]
    left_out = {OVERFIT} if overfit_in_head else set()
    if worse:
        left_out.add(COLD_START)
    lines += [f"note: {n.text}" for n in result.notes if n.kind not in left_out]
    return "\n".join(lines)


def judged_words(result, judge: str) -> str:
    """``validation run NAME`` or ``measured run NAME``: the run(s) the change is judged on."""
    return f"{'validation' if judge == 'validate' else 'measured'} run {result.run_names.get(judge, judge)}"


def worse_lines(result, judge: str) -> list[str]:
    """The head of a report whose change made the validation worse."""
    b, a = result.before[judge], result.after[judge]
    if len(result.validation_runs) > 1 and a["rms_um"] < b["rms_um"]:  # better together, worse on some run
        each = "; ".join(
            f"{r.name}: {r.before['rms_um']:.3g} → {r.after['rms_um']:.3g} µm RMS" for r in result.worse_runs
        )
        return [
            f"the augmented model is worse on {each} (the {len(result.validation_runs)} validation runs together: "
            f"{change_words(b['rms_um'], a['rms_um'])}); not recommended"
        ]
    judged = result.run_names.get(judge, judge)
    return [
        f"the augmented model is worse on {judged}: {b['rms_um']:.3g} → {a['rms_um']:.3g} µm RMS; not recommended",
        *(f"  ({n.text})" for n in result.notes if n.kind == COLD_START),
    ]


def selection_lines(result) -> list[str]:
    selection = result.selection
    if selection is None:
        return []
    how = "together with the effects" if selection.method == "joint" else f"by {selection.method}"
    lines = [
        f"inputs re-selected {how} on held-out conditions: {', '.join(selection.inputs) or 'none'} "
        f"({len(selection.inputs)} of {selection.of}); before/after compare with the model as given"
    ]
    if selection.nested_held_out_rms_um is not None:
        lines.append(
            f"  chosen again without each held-out condition, the selection predicts it with "
            f"{selection.nested_held_out_rms_um:.3g} µm RMS; the model as given, "
            f"{result.base_check.held_out_rms_um:.3g} µm"
        )
    return lines


def ridge_lines(result) -> list[str]:
    ridge = result.ridge
    if ridge is None:
        return []
    if not ridge.alpha:
        return ["ridge penalty alpha = 0 chosen (no penalty does best): the model is kept as given"]
    how = "given" if ridge.chosen == "given" else f"the least error on {ridge.folds}"
    return [
        f"coefficients refitted with the ridge penalty alpha = {ridge.alpha:g} ({how}); "
        "before/after compare with the model as given"
    ]


def reference_lines(result) -> list[str]:
    reference = result.reference
    if reference is not None and reference.rule_id == REFERENCE_STEADY:
        rms = reference.held_out_rms_um
        return [
            f"reference kept: absolute readings predict the held-out conditions with RMS "
            f"{change_words(rms['given'], rms['absolute'])}, but {reference.reason}"
        ]
    if reference is None or not reference.dropped:
        return []
    branch = reference.branch
    if branch is not None and branch.reason is None:
        return [branch_line(reference, branch)]
    rms = reference.held_out_rms_um
    effects = reference.after_effects
    when = f" (checked again with the first {effect_count(effects)} in)" if effects else ""
    grouped = (
        "judged with the groups as one, since each group's own intercept would absorb the air's level; "
        if reference.as_one_group
        else ""
    )
    return [
        f"reference dropped{when}: the error follows the absolute temperatures, not their rises over "
        f"`{reference.reference}` ({grouped}held-out RMS {change_words(rms['given'], rms['absolute'])}, "
        f"better on {reference.folds_improved} of {reference.n_folds} held-out folds); the model was "
        "refitted on absolute readings"
    ]


def branch_line(reference, branch) -> str:
    """The reference dropped because the diagnosis on absolute readings beat the one on rises."""
    rms = branch.held_out_rms_um
    n_given = len(branch.effects["given"])
    given = f"the {effect_count(n_given)} found on it" if n_given else "no effect"
    name = reference.reference
    if branch.as_well_with_fewer_coefficients:
        how = (
            f"the diagnosis on rises took `{name}` as measured back in, which frees the weight the reference "
            f"fixes; diagnosed again on absolute readings, the model predicts the held-out conditions as well "
            f"(RMS {change_words(rms['given'], rms['absolute'])}, within one standard error) with one "
            "coefficient fewer"
        )
    else:
        how = (
            f"diagnosed again on absolute readings, the model with its effects predicts the held-out conditions "
            f"with RMS {change_words(rms['given'], rms['absolute'])} against the model as given with {given} "
            f"(better on {branch.folds_improved} of {reference.n_folds} held-out folds)"
        )
    return (
        f"reference dropped: the error follows the absolute temperatures, not their rises over `{name}`: {how}; "
        "the model was refitted on absolute readings"
    )


def change_line(result, judge: str) -> str:
    b, a = result.before[judge], result.after[judge]
    return (
        f"{judged_words(result, judge)}: RMS {change_words(b['rms_um'], a['rms_um'])}, "
        f"max {b['max_um']:.3g} → {a['max_um']:.3g} µm"
    )


def effect_lines(result, judge: str) -> list[str]:
    """Each effect added, what it did on the held-out folds, and the change on the judged run."""
    lines = []
    for step in result.steps:
        c = step.candidate
        better = f"{c.n_folds_improved} of {len(c.fold_ratios)}"
        held_out = change_words(step.held_out_rms_before, step.held_out_rms_after)
        kind = "effect chosen with the inputs" if step.joint else "missing effect"
        lines.append(
            f"{kind}: {column_words(c.feature.column, result.ambient)}, {c.describe()} "
            f"(removes {100 * c.score:.0f} % of the held-out mean-square error, better on {better} held-out folds; "
            f"held-out RMS {held_out}{' against the inputs chosen before it' if step.joint else ''})"
        )
        if step.alternatives:
            others = "; ".join(f"{a.feature.column} {a.describe()}" for a in step.alternatives[:3])
            lines.append(f"  as well explained (within one standard error) by: {others}")
    lines.append(change_line(result, judge))
    if result.model.p > 0:
        lines.append(
            "each effect was added as one more input, with one coefficient for every group; the hard breaks "
            "kept, the groups refitted"
        )
    else:
        lines.append("each effect was added as one more input and the model refitted")
    return lines


def outcome_lines(result, judge: str) -> list[str]:
    """Why no effect was added: the best candidate refused, an over-fitting model, or nothing missing."""
    overfitted = result.base_check is not None and result.base_check.overfitted
    if result.refused:
        refusal = result.refused[0]
        c = refusal.candidate
        lines = [
            f"no effect added: the best candidate, {column_words(c.feature.column, result.ambient)}, {c.describe()} "
            f"(removes {100 * c.score:.0f} % of the held-out mean-square error), was refused: {refusal.reason}"
        ]
    elif overfitted:  # a model that over-fits hides what is missing
        lines = ["no effect added: no candidate explains a significant part of the held-out error"]
    else:
        lines = ["nothing missing: no candidate explains a significant part of the held-out error; no effect added"]
    if overfitted:
        check = result.base_check
        lines.append(
            f"the model over-fits (held-out RMS {check.held_out_rms_um:.3g} µm against "
            f"{check.in_sample_rms_um:.3g} µm in sample): {check.advice}"
        )
    if result.changed:
        lines.append(change_line(result, judge))
    return lines


def candidate_table(candidates) -> list[str]:
    lines = [f"{'candidate':<24} {'transform':<40} {'score':>6} {'folds':>6} {'explained µm':>15}"]
    for c in candidates:
        lines.append(
            f"{c.feature.column:<24} {c.describe():<40} {c.score:>6.3f} "
            f"{c.n_folds_improved:>3d}/{len(c.fold_ratios):<2} {c.explained_rms_um:>15.3g}"
        )
    return lines


def metrics_lines(result) -> list[str]:
    """The error metrics before and after on each kind of run (and each validation run, when several)."""
    names = result.run_names
    lines = []
    for key in result.before:
        b, a = result.before[key], result.after[key]
        lines.append(
            f"{key:<9} {names.get(key, key)}: RMS {change_words(b['rms_um'], a['rms_um'])}, max {b['max_um']:.4g} → "
            f"{a['max_um']:.4g} µm, R {b['R_um']:.4g} → {a['R_um']:.4g} µm"
        )
        if key == "validate" and len(result.validation_runs) > 1:
            lines += [
                f"  {r.name}: RMS {change_words(r.before['rms_um'], r.after['rms_um'])}, max "
                f"{r.before['max_um']:.4g} → {r.after['max_um']:.4g} µm"
                for r in result.validation_runs
            ]
    return lines


def residual_line(result) -> str:
    lb_b, lb_a = result.checks_before["ljung_box"], result.checks_after["ljung_box"]
    dr_b, dr_a = result.checks_before["drift"], result.checks_after["drift"]
    return (
        f"residual on {result.run_names.get('data', 'data')}: Ljung–Box Q({lb_b['lags']}) {lb_b['Q']:.0f} → "
        f"{lb_a['Q']:.0f}; drift {dr_b['slope_um_per_h']:.3g} → {dr_a['slope_um_per_h']:.3g} µm/h "
        f"(HAC p {dr_b['p_value']:.2g} → {dr_a['p_value']:.2g})"
    )
