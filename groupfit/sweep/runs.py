"""One run of a study: load the data, pick the sensors, fit, and report a plain dict.

:func:`execute_run` is a pure function of the run specification (and of the
data file's bytes, whose hash is part of the specification), so it gives the
same result on any process or machine. It never raises for a run that cannot
be done (an infeasible p for the data, a selection that fails …): the result
then has ``status = "failed"`` and the message, and the study goes on.

Work shared by runs on the same process is cached: the parsed data, the sensor
selections, and the exact optimum that GA runs are compared with (one dynamic
programme answers every p, so GA runs over p and seeds reuse it).
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import time
from functools import lru_cache
from pathlib import Path

import numpy as np

from groupfit.data import PERIOD_TOLERANCE, Run, load_run, measured_rows
from groupfit.errors import InputError
from groupfit.grouping import Constraints
from groupfit.heldout.selection import select_sensors
from groupfit.models.grouped import GroupedRegressor
from groupfit.objective import SegmentCost
from groupfit.reference import default_reference, referenced
from groupfit.search.exact import ExactResult, exact_is_cheap, solve_exact
from groupfit.sweep.config import canonical_json
from groupfit.textlayout import read_text_table

REFERENCE_PMAX = 8
"""The exact reference is solved for every p up to at least this many breaks at once."""

_exact_references: dict[tuple, ExactResult] = {}
_selections: dict[tuple[str, str], tuple[str, ...]] = {}


def execute_run(spec: dict, path: str, content: bytes | None = None) -> dict:
    """Do one run and return its result.

    Parameters
    ----------
    spec : dict
        A run specification (:attr:`groupfit.sweep.config.RunSpec.spec`).
    path : str
        The data file; read unless ``content`` is given.
    content : bytes, optional
        The data file's bytes (sent to remote workers that cannot read ``path``).

    Returns
    -------
    dict
        ``status`` ("done" or "failed"), ``error`` (message or None), and for
        a done run ``sensors``, ``n_samples``, ``objective``, ``breaks``,
        ``soft_groups``, ``coefficients``, ``search`` (method details), the
        exact reference (``exact_objective``, ``exact_breaks``,
        ``gap_percent``, for GA runs when certified), ``timings`` (seconds per
        stage) and ``worker``.
    """
    start = time.perf_counter()
    timings: dict[str, float] = {}
    result: dict = {"status": "failed", "error": None, "worker": f"{socket.gethostname()}:{os.getpid()}"}
    try:
        run = _load(spec, path, content)
        timings["load"] = time.perf_counter() - start
        mark = time.perf_counter()
        sensors = resolve_sensors(spec, run)
        timings["select"] = time.perf_counter() - mark
        result.update(fit_run(spec, run, sensors, timings))
        result["status"] = "done"
    except InputError as exc:
        result["error"] = str(exc)
    except Exception as exc:  # noqa: BLE001 - any failure of one run is recorded, not fatal
        result["error"] = f"{type(exc).__name__}: {exc}"
    timings["total"] = time.perf_counter() - start
    result["timings"] = timings
    return result


def fit_run(spec: dict, run: Run, sensors: list[str], timings: dict[str, float]) -> dict:
    """Fit the grouped model of one run; with a GA search, also compare with the exact optimum."""
    model, search = spec["model"], spec["search"]
    # rises over the run's ambient, T_amb or one named as the air's (groupfit.reference), as fit and compare
    # default to; they may drop it by the next-run estimate when the ambient moves (docs/nextrun.md), a sweep
    # keeps it so that every grid point fits the same inputs
    reference = default_reference(run.frame, model.get("reference"), sensors)
    reference = None if reference in sensors else reference  # an input is never its own reference
    X = referenced(run.frame[sensors].to_numpy(dtype=float), reference, run.frame, str(run.source))
    y = run.error
    estimator = estimator_for(spec)
    mark = time.perf_counter()
    estimator.fit(X, y)
    timings["fit"] = time.perf_counter() - mark
    coefficients = [
        ([float(b0)] if estimator.fit_intercept else []) + [float(v) for v in slopes]
        for b0, slopes in zip(estimator.intercept_, estimator.coef_)
    ]
    info = {k: v for k, v in estimator.search_.items() if k != "method"}
    result = {
        "sensors": list(sensors),
        "reference": reference,
        "n_samples": int(run.n_samples),
        "n_coef": int(estimator.n_coef),
        "objective": float(estimator.objective_value_),
        "search_objective": float(info.pop("search_objective")),
        "breaks": list(estimator.breaks_),
        "soft_groups": [list(g) for g in estimator.soft_groups_],
        "coefficients": coefficients,
        "search": info,
        "exact_objective": None,
        "exact_breaks": None,
        "gap_percent": None,
    }
    if search["method"] == "exact":
        result["exact_objective"] = result["search_objective"]
        result["exact_breaks"] = list(estimator.breaks_)
        result["gap_percent"] = 0.0
    elif wants_reference(search.get("certify", "auto"), run.n_samples, model["objective"]):
        mark = time.perf_counter()
        reference = exact_reference(spec, X, y, sensors, model["p"])
        timings["exact"] = time.perf_counter() - mark
        best = reference.objective[model["p"]]
        result["exact_objective"] = float(best)
        result["exact_breaks"] = list(reference.breaks[model["p"]])
        result["gap_percent"] = 100.0 * (result["search_objective"] - best) / best if best > 0 else 0.0
    return result


def estimator_for(spec: dict) -> GroupedRegressor:
    """The GroupedRegressor a run specification describes (no automatic certification)."""
    return GroupedRegressor.from_config(spec, certify=False)


def wants_reference(certify, n_samples: int, objective: str) -> bool:
    """Whether a GA run is compared with the exact optimum ("auto": when that is cheap)."""
    if certify == "auto":
        return exact_is_cheap(n_samples, objective)
    return bool(certify)


def exact_reference(spec: dict, X: np.ndarray, y: np.ndarray, sensors: list[str], p: int) -> ExactResult:
    """The exact optimum for every p up to max(p, REFERENCE_PMAX), cached per process."""
    model = spec["model"]
    key = (spec["data"]["sha256"], tuple(sensors), model["n"], model["c"], model["objective"], model["intercept"])
    cached = _exact_references.get(key)
    if cached is not None and p in cached.objective:
        return cached
    n_coef = X.shape[1] + int(model["intercept"])
    constraints = Constraints.for_model(len(y), model["n"], model["c"], n_coef)
    cost = SegmentCost(X, y, n=model["n"], objective=model["objective"], fit_intercept=model["intercept"])
    reference = solve_exact(cost, constraints, max(p, REFERENCE_PMAX))
    _exact_references[key] = reference
    return reference


def resolve_sensors(spec: dict, run: Run) -> list[str]:
    """The run's input columns: the names given, or those a selection picks."""
    sensors = spec["sensors"]
    if "names" in sensors:
        return list(sensors["names"])
    return list(_selected(spec["data"]["sha256"], canonical_json(sensors), run))


def _selected(sha256: str, selection_json: str, run: Run) -> tuple[str, ...]:
    key = (sha256, selection_json)
    if key not in _selections:
        selection = json.loads(selection_json)
        X = run.frame[selection["candidates"]].to_numpy(dtype=float)
        _selections[key] = tuple(
            select_sensors(
                X,
                run.error,
                selection["candidates"],
                selection["select"],
                selection["k"],
                folds=selection["folds"],
                cluster_corr=selection["cluster_corr"],
            )
        )
    return _selections[key]


def _load(spec: dict, path: str, content: bytes | None) -> Run:
    data = spec["data"]
    glitches = bool(data.get("glitches_left_out"))
    clock = (data.get("period_tolerance", PERIOD_TOLERANCE), data.get("resample_s"), glitches)
    return _parsed_run(data["sha256"], data["time"], data["error"], clock, path, content)


@lru_cache(maxsize=4)
def _parsed_run(
    sha256: str, time_column: str, error_column: str, clock: tuple, path: str, content: bytes | None
) -> Run:
    if content is None:
        try:
            content = Path(path).read_bytes()
        except OSError as exc:
            raise InputError(f"{path}: cannot read the data file ({exc.strerror})") from None
    if hashlib.sha256(content).hexdigest() != sha256:
        raise InputError(f"{path}: the data file has changed since the study was read; start the sweep again")
    frame, _ = read_text_table(content)
    frame.columns = [str(c).strip() for c in frame.columns]
    tolerance, resample, drop_glitches = clock
    run = load_run(
        frame,
        temps=[],
        time=time_column,
        error=error_column,
        name=Path(path).stem,
        period_tolerance=tolerance,
        resample=resample,
        drop_glitches=drop_glitches,
    )
    return measured_rows(run)  # glitches left out are rows not measured, as fit leaves them out
