"""What ``groupfit fit`` found, as an object: the estimator, its model file, and the printed summary."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from groupfit.data import Run
from groupfit.fast_response import without_stage
from groupfit.grouping import served_ranges
from groupfit.heldout.expect import CHOICE_RULE
from groupfit.heldout.records import OverfitCheck, RidgeSetting
from groupfit.model import ModelFile
from groupfit.models.grouped import GroupedRegressor


@dataclass
class FitResult:
    """A grouped model fitted on a run.

    ``selection``: how ``--p auto`` chose p (:func:`groupfit.models.select_p.choose_p`), when it did;
    ``input_selection``: how ``--select`` chose the inputs, when it did.
    """

    estimator: GroupedRegressor
    run: Run
    model: ModelFile
    selection: dict[str, Any] | None = None
    input_selection: dict[str, Any] | None = None
    intervals: Any = None
    """The breaks' confidence intervals (a :class:`groupfit.inference.BreakIntervalReport`), when computed."""
    ridge: RidgeSetting | None = None
    """How ``--ridge`` set the penalty (:func:`groupfit.diagnose.select.ridge_setting`), when it did."""
    held_out: OverfitCheck | None = None
    """The model's error on held-out conditions or runs (:func:`groupfit.heldout.check.held_out_check`)."""
    statistics: dict[str, Any] | None = None
    """A global regression's tests (:func:`groupfit.models.mlr.ols_statistics`), when p = 0 by least squares."""
    expectation: Any = None
    """The expected next-run error (a :class:`groupfit.heldout.expect.NextRunExpectation`), when estimated."""
    choice: Any = None
    """The expectation that chose p among several candidates (least squares), when p was chosen by it; the
    model's own figures are in ``expectation`` (they differ when the chosen global model got a penalty)."""

    no_estimate: str = ""
    """Why the next-run error was not estimated, when it was not (``fit --json`` then carries its keys as null)."""

    @property
    def p_choice(self):
        """The expectation p was chosen by: ``choice``, else ``expectation``."""
        return self.choice if self.choice is not None else self.expectation

    def to_json(self) -> dict[str, Any]:
        """The model file object plus ``search`` (and ``p_selection``): ``fit --json``."""
        result = {**self.model.to_dict(), "search": self.estimator.search_}
        if self.intervals is not None:
            result["break_intervals"] = self.intervals.to_json()
        if self.selection is not None:
            result["p_selection"] = self.selection
        if self.input_selection is not None:
            result["input_selection"] = self.input_selection
        if self.ridge is not None:
            result["ridge"] = self.ridge.to_json()
        if self.held_out is not None:
            result["held_out"] = self.held_out.to_json()
        if self.statistics is not None:
            result["statistics"] = self.statistics
        if self.expectation is None:
            result.update(
                expected_next_run_rms_um=None,
                expected_next_run_range_um=None,
                expected_next_run_method=f"not estimated: {self.no_estimate or 'no estimate was asked for'}",
            )
        else:
            result.update(self.expectation.training())
            if len(self.p_choice.candidates) > 1:
                result["p_selection"] = {"rule": "next-run", **self.p_choice.to_json()}
        return result

    def summary(self) -> str:
        """Breaks, groups, coefficients and residuals, as ``groupfit fit`` prints them."""
        report = fit_report(self.estimator, self.run, self.model, self.intervals)
        if self.selection is not None:
            report = selection_summary(self.selection) + "\n" + report
        if self.input_selection is not None and self.input_selection["method"] == "backward":
            report = backward_summary(self.input_selection) + "\n" + report
        elif self.input_selection is not None:
            chosen = self.input_selection
            report = (
                f"inputs  {chosen['method']} selection ({chosen['folds']}): "
                f"{', '.join(chosen['inputs'])} of {chosen['candidates']}\n" + report
            )
        if self.ridge is not None:
            report = ridge_summary(self.ridge) + "\n" + report
        if self.statistics is not None:
            report += "\n" + statistics_summary(self.statistics)
        if self.expectation is not None:
            report = choice_summary(self.p_choice) + report
        if self.held_out is not None:
            penalised = self.ridge is not None and (self.ridge.alpha > 0 or self.ridge.chosen != "given")
            report += "\n" + held_out_summary(self.held_out, penalised=penalised)
        if self.expectation is not None:
            report += "\n" + self.expectation.line()
        return report


def backward_summary(selection: dict) -> str:
    dropped = ", ".join(f"{d['name']} ({_why_dropped(d)})" for d in selection["dropped"])
    return (
        f"inputs  backward elimination at alpha = {selection['alpha']:g}: kept {', '.join(selection['inputs'])} "
        f"of {selection['candidates']}; dropped {dropped or 'none'}"
    )


def _why_dropped(dropped: dict) -> str:
    if dropped.get("t") is None:
        return f"linearly dependent on {', '.join(dropped.get('dependent_on') or ['the others'])}"
    return f"t = {dropped['t']:.2f}, p = {dropped['p_value']:.3g}"


def statistics_summary(stats: dict) -> str:
    """The tests as ``fit --p 0`` prints them."""
    terms = ", ".join(f"{t['name']} t = {t['t']:.3g} (p = {t['p_value']:.3g})" for t in stats["terms"])
    f_text = (
        f"F({stats['f_dof'][0]:g}, {stats['f_dof'][1]:g}) = {stats['f_value']:.4g} (p = {stats['f_p_value']:.3g}); "
        if stats["f_value"] is not None
        else ""
    )
    centred = "" if stats["centred"] else " (uncentred: no intercept)"
    dependent = stats.get("dependent_inputs")
    if dependent:
        terms = (
            f"none per input: {', '.join(dependent)} are linearly dependent (a sensor logged twice, or one the "
            "sum of others), so their coefficients split one effect arbitrarily; leave one out (--temps)"
        )
    return (
        f"tests   {terms}\n        {f_text}R² = {stats['r_squared']:.5f}, adjusted R² = "
        f"{stats['adjusted_r_squared']:.5f}{centred}, σ = {stats['sigma_um']:.3g} µm"
    )


def choice_summary(expectation) -> str:
    """How p was chosen by the expected next-run error, when it was chosen among several, or why there was
    only one (else nothing)."""
    candidates, not_tried = expectation.candidates, expectation.not_tried
    untried = expectation.untried()
    if len(candidates) < 2:
        return f"p       {candidates[0]}: {untried}\n" if untried else ""
    table = ", ".join(f"p={p}: {expectation.expected(i)[0]:.3g} µm" for i, p in enumerate(candidates))
    chosen = candidates[expectation.chosen]
    line = f"p       {chosen}: {CHOICE_RULE} (expected next-run RMS {table}{'; ' + untried if untried else ''})\n"
    if chosen > 0 and chosen == max(candidates) and not not_tried:
        line += (
            f"note    p = {chosen} is the largest p tried (the edge of the range): a larger p may hold better; "
            "raise --pmax to look further\n"
        )
    return line


def ridge_summary(ridge: RidgeSetting) -> str:
    """One line on the ridge penalty: given, or chosen on held-out data with the error of every penalty tried."""
    if ridge.chosen == "given":
        return f"ridge   penalty alpha = {ridge.alpha:g} (given)"
    table = ", ".join(f"{row.alpha:g}: {row.held_out_rms_um:.3g}" for row in ridge.held_out)
    default = "; the default for a global model, --ridge 0 for least squares" if ridge.default else ""
    return (
        f"ridge   penalty alpha = {ridge.alpha:g}, the least held-out error ({ridge.folds}; held-out RMS µm by "
        f"alpha: {table}){default}"
    )


def held_out_summary(check: OverfitCheck, *, penalised: bool = False) -> str:
    """The held-out line of a model, with a note when it over-fits."""
    line = (
        f"check   held-out RMS {check.held_out_rms_um:.4g} µm against {check.in_sample_rms_um:.4g} µm in sample "
        f"({check.folds})"
    )
    if check.overfitted:
        hold_better = "fewer inputs (--select forward) or a ridge penalty (--ridge auto) hold better"
        if penalised:  # a penalty was applied, or chosen on held-out data as none
            hold_better = "fewer inputs (--select forward) may hold better"
        if check.grouped:
            hold_better = "try fewer groups (--p 0) or fewer inputs (--select forward)"
        line += (
            "\nnote    the model over-fits: expect the held-out error on the next run, not the in-sample one; "
            + hold_better
        )
    return line


def selection_rule(selection: dict) -> str:
    """The in-sample rule ``--choose bic|target`` chose p by, in words."""
    if selection["rule"] == "bic":
        return "smallest BIC (in sample)"
    return f"fewest breaks with R <= {selection['target_um']:.4g} µm"


def selection_summary(selection: dict) -> str:
    table = ", ".join(
        f"p={p}: R {r:.4g} µm, BIC {b:.1f}" for p, (r, b) in enumerate(zip(selection["R_um"], selection["bic"]))
    )
    line = f"p auto  {selection_rule(selection)}: p = {selection['p']}  ({table})"
    largest = len(selection["R_um"]) - 1
    if largest > 0 and selection["p"] == largest:
        line += (
            f"\nnote    p = {largest} is the largest p tried (the edge of the range): a larger p may fit better; "
            "raise --pmax to look further"
        )
    return line


def fit_report(estimator: GroupedRegressor, run: Run, model: ModelFile, intervals=None) -> str:
    """The table ``groupfit fit`` prints (without the files it wrote): the model's coefficients, without the
    fast-response stage for probe checks (:mod:`groupfit.fast_response`), which is reported on its own line."""
    model = without_stage(model)
    unit = "µm" if estimator.objective == "sae" else "µm²"
    search = estimator.search_
    lines = [
        f"run     {run.source}: N = {run.n_samples} samples every {run.period:g} s; "
        f"inputs {', '.join(run.temp_names)}{_relative_to(run)} -> {run.error_name}",
        f"model   p = {estimator.p}, n = {estimator.n}, c = {estimator.c:g}, M = {estimator.n_coef} "
        f"({'with' if estimator.fit_intercept else 'no'} intercept), objective {estimator.objective}, "
        f"hard groups > {estimator.c * estimator.n_coef:g} samples",
        "search  " + search_summary(search, unit),
        "",
    ]
    names = (["const"] if estimator.fit_intercept else []) + list(run.temp_names)
    header = ["group", "hard", "soft", "serves"] + names + [f"R ({unit})"]
    served = served_ranges(estimator.breaks_, estimator.n_samples_fit_, estimator.n)
    rows = []
    for g, (hard, soft, serve) in enumerate(zip(estimator.hard_groups_, estimator.soft_groups_, served)):
        coefficients = model.coefficients[g]
        rows.append(
            [str(g + 1), _span(hard), _span(soft), _span(serve)]
            + [f"{v:.5g}" for v in coefficients]
            + [f"{estimator.group_objective_[g]:.4f}"]
        )
    if intervals is not None:
        header.insert(2, f"break {100 * intervals.level:g} % CI")
        for g, row in enumerate(rows):
            row.insert(2, intervals.text_for(estimator.breaks_[g]) if g < len(estimator.breaks_) else "")
    widths = [max(len(r[i]) for r in [header] + rows) for i in range(len(header))]
    for row in [header] + rows:
        lines.append("  ".join(cell.rjust(width) for cell, width in zip(row, widths)))
    metrics = model.training
    lines += [
        "",
        f"breaks  {estimator.breaks_}   Rg = {estimator.objective_value_:.6g} {unit}   "
        f"RMS {metrics['rms_um']:.4g} µm   max |e| {metrics['max_um']:.4g} µm",
        f"switch  criterion sensor {model.switching.criterion}",
    ]
    if intervals is not None and estimator.breaks_:
        lines.append(f"breaks  {100 * intervals.level:g} % intervals: {intervals.summary(run.n_samples)}")
    return "\n".join(lines)


def search_summary(search: dict, unit: str) -> str:
    if search["method"] == "exact" and search["evaluations"] == 1:
        return f"exact (one least-squares fit, no break to search), {search['seconds']:.2f} s"
    if search["method"] == "exact":
        return f"exact (dynamic programming): {search['evaluations']} segment costs, {search['seconds']:.2f} s"
    text = (
        f"ga (DEAP, seed {search['seed']}): {search['generations']} generations ({search['stopped']}), "
        f"{search['evaluations']} evaluations, {search['seconds']:.2f} s"
    )
    if "gap_percent" in search:
        text += (
            f"; exact optimum {search['exact_objective']:.6g} {unit} at {search['exact_breaks']}, "
            f"GA gap {search['gap_percent']:.3g} % (certified in {search['exact_seconds']:.1f} s)"
        )
    elif "exact_skipped" in search:
        text += f"; not checked against the exact optimum: {search['exact_skipped']}"
    return text


def _relative_to(run: Run) -> str:
    """How the inputs are taken (:mod:`groupfit.reference`), for the report."""
    reference = getattr(run, "reference", None)
    if reference is None:
        return " (absolute)"
    return " (minus their first reading)" if reference == "start" else f" (minus {reference})"


def _span(pair) -> str:
    return f"{pair[0]}-{pair[1]}"
