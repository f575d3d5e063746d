"""Summaries of a study: tables (CSV, Markdown) and figures (PNG).

Written to a folder by :func:`write_report`:

``runs.csv``
    One line per run: its settings, status, Rg, the exact optimum, the GA gap,
    the breaks, the seconds.
``summary.csv`` / ``summary.md``
    One line per setting and p (data set, sensors, objective, n, c): the best
    Rg found, the exact optimum, how many GA runs came within 0.1 % of it, and
    how many distinct break vectors the runs found (over seeds and budgets).
    The Markdown file adds GA success against budget and the failed runs.
``objective_vs_p.png``
    Best Rg against p, one line per (n, c) and sensor set, one panel per data
    set and objective (the paper's Table 1 as a curve).
``break_stability.png``
    The hard break positions found for each p, over seeds and budgets; a dot's
    size is the share of runs that put a break there.
``ga_success.png``
    Share of GA runs within 0.1 % of the exact optimum against the nominal
    budget (population size × maximum generations), one line per p.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from groupfit.io import atomic_write_files, save_figure

SUCCESS_PERCENT = 0.1
"""A GA run succeeds when its Rg is within this many percent of the exact optimum."""
SETTING = ["dataset", "sensor_set", "objective_kind", "intercept", "n", "c"]
REPORT_HEADERS = {"runs.csv": "run_hash,", "summary.csv": f"{SETTING[0]},"}
"""How the header lines of the report's tables start (a table of those names with another header is the user's)."""
MAX_PANELS = 6


def sensor_label(spec: dict, used: Sequence[str] | None) -> str:
    """Short name of a sensor option: the names (up to four) or the selection and what it picked."""
    names = list(used or spec.get("names") or [])
    listed = ",".join(names) if len(names) <= 4 else f"{len(names)} sensors"
    if "select" in spec:
        return f"{spec['select']} k={spec['k']}" + (f" ({listed})" if names else "")
    return listed


def runs_frame(rows: list[dict]) -> pd.DataFrame:
    """The study's rows as a table, GA gaps filled in from exact runs where a run has none."""
    records = []
    for row in rows:
        result = row.get("result") or {}
        records.append(
            {
                "run_hash": row["run_hash"],
                "dataset": row["dataset"],
                "sensor_set": sensor_label(row["sensors_spec"], row.get("sensors")),
                "sensors": ",".join(row.get("sensors") or []),
                "search": row["search"],
                "objective_kind": row["objective_kind"],
                "intercept": bool(row["intercept"]),
                "p": int(row["p"]),
                "n": int(row["n"]),
                "c": float(row["c"]),
                "seed": row["seed"],
                "population_size": row["population_size"],
                "max_generations": row["max_generations"],
                "polish": (row.get("config") or {}).get("search", {}).get("polish"),
                "budget": (row["population_size"] or 0) * (row["max_generations"] or 0) or None,
                "status": row["status"],
                "objective": row["objective"],
                "search_objective": result.get("search_objective"),
                "exact_objective": row["exact_objective"],
                "gap_percent": row["gap_percent"],
                "breaks": json.dumps(row["breaks"]) if row["breaks"] is not None else "",
                "seconds": row["seconds"],
                "error": row["error"] or "",
            }
        )
    frame = pd.DataFrame.from_records(records)
    if frame.empty:
        return frame
    _fill_gaps_from_exact_runs(frame)
    frame["success"] = np.where(
        frame["gap_percent"].notna(), frame["gap_percent"].astype(float) <= SUCCESS_PERCENT, np.nan
    )
    return frame


def _fill_gaps_from_exact_runs(frame: pd.DataFrame) -> None:
    done = frame["status"] == "done"
    exact = frame[done & (frame["search"] == "exact")]
    optimum = exact.groupby(["dataset", "sensors", "objective_kind", "intercept", "n", "c", "p"])[
        "exact_objective"
    ].min()
    for index in frame.index[done & (frame["search"] == "ga") & frame["gap_percent"].isna()]:
        row = frame.loc[index]
        key = (row["dataset"], row["sensors"], row["objective_kind"], row["intercept"], row["n"], row["c"], row["p"])
        if key in optimum.index:
            best = float(optimum.loc[key])
            frame.loc[index, "exact_objective"] = best
            frame.loc[index, "gap_percent"] = 100.0 * (row["search_objective"] - best) / best if best > 0 else 0.0


def summary_frame(runs: pd.DataFrame) -> pd.DataFrame:
    """One line per setting and p over the done runs."""
    done = runs[runs["status"] == "done"]
    lines = []
    for key, group in done.groupby(SETTING + ["p"], sort=True):
        ga = group[group["search"] == "ga"]
        judged = ga[ga["success"].notna()]
        best = group.loc[group["objective"].idxmin()]
        lines.append(
            {
                **dict(zip(SETTING + ["p"], key)),
                "runs": len(group),
                "best_objective": float(best["objective"]),
                "best_breaks": best["breaks"],
                "exact_objective": float(group["exact_objective"].min())
                if group["exact_objective"].notna().any()
                else np.nan,
                "ga_runs": len(ga),
                "ga_within_0.1pct": int(judged["success"].astype(bool).sum()) if len(judged) else np.nan,
                "ga_judged": len(judged),
                "distinct_breaks": group["breaks"].nunique(),
                "break_spread": break_spread(group["breaks"]),
            }
        )
    return pd.DataFrame.from_records(lines)


def break_spread(breaks_json: pd.Series) -> float:
    """Largest standard deviation of any break position over the runs (samples)."""
    vectors = [json.loads(b) for b in breaks_json if b]
    if len(vectors) < 2 or not vectors[0]:
        return 0.0
    return float(np.max(np.std(np.asarray(vectors, dtype=float), axis=0)))


def success_frame(runs: pd.DataFrame) -> pd.DataFrame:
    """GA success rate per local-search setting, budget and p."""
    keys = ["polish", "population_size", "max_generations", "budget", "p"]
    ga = runs[(runs["status"] == "done") & (runs["search"] == "ga") & runs["success"].notna()]
    if ga.empty:
        return pd.DataFrame(columns=keys + ["runs", "successes", "rate"])
    table = (
        ga.assign(success=ga["success"].astype(bool), polish=ga["polish"].astype(bool))
        .groupby(keys)["success"]
        .agg(runs="count", successes="sum")
        .reset_index()
    )
    table["rate"] = table["successes"] / table["runs"]
    return table


def write_report(rows: list[dict], folder: str | Path, title: str = "study") -> list[Path]:
    """Write the tables and figures of a study; return the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    runs = runs_frame(rows)
    if runs.empty:
        return atomic_write_files({folder / "summary.md": f"# {title}\n\ngroupfit sweep: no runs recorded.\n"})
    summary = summary_frame(runs)
    success = success_frame(runs)
    written = atomic_write_files(
        {
            folder / "runs.csv": runs.to_csv(index=False),
            folder / "summary.csv": summary.to_csv(index=False),
            folder / "summary.md": markdown_report(title, runs, summary, success),
        }
    )
    if not summary.empty:
        written.append(plot_objective_vs_p(summary, folder / "objective_vs_p.png"))
        written.append(plot_break_stability(runs, folder / "break_stability.png"))
    if not success.empty:
        written.append(plot_success(success, folder / "ga_success.png"))
    return written


def markdown_report(title: str, runs: pd.DataFrame, summary: pd.DataFrame, success: pd.DataFrame) -> str:
    counts = runs["status"].value_counts()
    lines = [
        f"# {title}",
        "",
        f"groupfit sweep: {len(runs)} runs, {int(counts.get('done', 0))} done, {int(counts.get('failed', 0))} failed.",
        "",
        "## Objective against p",
        "",
        "Best Rg over all runs of a setting; exact = the dynamic-programming optimum; "
        f"GA ok = GA runs within {SUCCESS_PERCENT} % of it; distinct = break vectors found; "
        "spread = largest standard deviation of a break position (samples).",
        "",
    ]
    header = ["data", "sensors", "obj", "n", "c", "p", "best Rg", "exact Rg", "GA ok", "distinct", "spread", "breaks"]
    table = [header]
    for _, s in summary.iterrows():
        ok = f"{int(s['ga_within_0.1pct'])}/{int(s['ga_judged'])}" if s["ga_judged"] else "-"
        table.append(
            [
                s["dataset"],
                s["sensor_set"],
                s["objective_kind"],
                str(s["n"]),
                f"{s['c']:g}",
                str(s["p"]),
                f"{s['best_objective']:.6g}",
                "-" if np.isnan(s["exact_objective"]) else f"{s['exact_objective']:.6g}",
                ok,
                str(s["distinct_breaks"]),
                f"{s['break_spread']:.1f}",
                s["best_breaks"],
            ]
        )
    lines += _markdown_table(table)
    if not success.empty:
        lines += [
            "",
            "## GA success against budget",
            "",
            "Budget = population size × maximum generations (the GA may stop earlier on stagnation).",
            "",
        ]
        table = [["polish", "population", "generations", "budget", "p", "runs", f"within {SUCCESS_PERCENT} %", "rate"]]
        for _, s in success.iterrows():
            table.append(
                [
                    "yes" if s["polish"] else "no",
                    str(int(s["population_size"])),
                    str(int(s["max_generations"])),
                    str(int(s["budget"])),
                    str(int(s["p"])),
                    str(int(s["runs"])),
                    str(int(s["successes"])),
                    f"{s['rate']:.0%}",
                ]
            )
        lines += _markdown_table(table)
    failed = runs[runs["status"] == "failed"]
    if not failed.empty:
        lines += ["", "## Failed runs", ""]
        table = [["run", "data", "p", "n", "c", "search", "message"]]
        for _, f in failed.iterrows():
            table.append(
                [
                    f["run_hash"][:12],
                    f["dataset"],
                    str(f["p"]),
                    str(f["n"]),
                    f"{f['c']:g}",
                    f["search"],
                    f["error"].replace("|", "/"),
                ]
            )
        lines += _markdown_table(table)
    return "\n".join(lines) + "\n"


def _markdown_table(rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(rows[0]) + " |", "|" + "|".join("---" for _ in rows[0]) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows[1:]]
    return out


def _panels(count: int):
    """A figure of its own (no pyplot, no global backend) with ``count`` panels."""
    from matplotlib.figure import Figure

    columns = min(count, 3)
    rows = int(np.ceil(count / columns))
    fig = Figure(figsize=(4.6 * columns, 3.6 * rows), layout="constrained")
    axes = fig.subplots(rows, columns, squeeze=False)
    for axis in axes.flat[count:]:
        axis.set_visible(False)
    return fig, list(axes.flat)


def plot_objective_vs_p(summary: pd.DataFrame, path: Path) -> Path:
    """Best Rg against p per (n, c) and sensor set; one panel per data set and objective."""
    panels = list(summary.groupby(["dataset", "objective_kind"], sort=True))[:MAX_PANELS]
    fig, axes = _panels(len(panels))
    for axis, ((dataset, objective), group) in zip(axes, panels):
        for (sensors, n, c, intercept), line in group.groupby(["sensor_set", "n", "c", "intercept"], sort=True):
            line = line.sort_values("p")
            label = f"n={n}, c={c:g}" + ("" if group["sensor_set"].nunique() == 1 else f", {sensors}")
            if group["intercept"].nunique() > 1:
                label += "" if intercept else ", no intercept"
            axis.plot(line["p"], line["best_objective"], marker="o", label=label)
        axis.set_title(f"{dataset}: {objective}")
        axis.set_xlabel("p (hard breaks)")
        axis.set_ylabel("Rg (µm)" if objective == "sae" else "Rg (µm²)")
        axis.xaxis.get_major_locator().set_params(integer=True)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    save_figure(fig, path, dpi=110)
    return path


def plot_break_stability(runs: pd.DataFrame, path: Path) -> Path:
    """Break positions found for each p, over seeds and budgets; dot size = share of runs."""
    done = runs[(runs["status"] == "done") & (runs["p"] > 0)]
    panels = list(done.groupby(SETTING, sort=True))[:MAX_PANELS]
    fig, axes = _panels(max(1, len(panels)))
    for axis, (key, group) in zip(axes, panels):
        for p, at_p in group.groupby("p"):
            positions = [b for text in at_p["breaks"] for b in json.loads(text)]
            values, counts = np.unique(positions, return_counts=True)
            share = counts / len(at_p)
            axis.scatter(
                np.full(len(values), p),
                values,
                s=12 + 80 * share,
                alpha=0.6,
                color="tab:blue",
                label="found (size: share of runs)" if p == group["p"].min() else None,
            )
            exact = at_p[at_p["search"] == "exact"]
            if not exact.empty:
                optimum = json.loads(exact["breaks"].iloc[0])
                axis.scatter(
                    np.full(len(optimum), p),
                    optimum,
                    marker="x",
                    s=50,
                    color="tab:red",
                    label="exact optimum" if p == group["p"].min() else None,
                )
        axis.legend(fontsize=7, loc="upper left")
        dataset, sensors, objective, _, n, c = key
        axis.set_title(f"{dataset}, {sensors}: {objective}, n={n}, c={c:g}", fontsize=9)
        axis.set_xlabel("p (hard breaks)")
        axis.set_ylabel("break position (sample)")
        axis.xaxis.get_major_locator().set_params(integer=True)
        axis.grid(alpha=0.3)
    save_figure(fig, path, dpi=110)
    return path


def plot_success(success: pd.DataFrame, path: Path) -> Path:
    """GA success rate against nominal budget, one line per p and one over all p; a panel per polish setting."""
    panels = list(success.groupby("polish", sort=True))
    fig, axes = _panels(len(panels))
    for axis, (polish, group) in zip(axes, panels):
        for p, line in group.groupby("p"):
            by_budget = line.groupby("budget")[["successes", "runs"]].sum()
            axis.plot(by_budget.index, by_budget["successes"] / by_budget["runs"], marker="o", label=f"p={p}")
        overall = group.groupby("budget")[["successes", "runs"]].sum()
        axis.plot(overall.index, overall["successes"] / overall["runs"], color="black", lw=2, label="all p")
        axis.set_xscale("log")
        axis.set_ylim(-0.05, 1.05)
        axis.set_title("GA with local search" if polish else "GA alone (no local search)", fontsize=10)
        axis.set_xlabel("budget: population × max generations")
        axis.set_ylabel(f"share within {SUCCESS_PERCENT} % of exact")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    save_figure(fig, path, dpi=110)
    return path
