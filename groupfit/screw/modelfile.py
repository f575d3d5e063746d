"""The ball-screw model file (JSON, ``"format": "groupfit-ballscrew/1"``, ``"kind": "ballscrew"``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.errors import InputError
from groupfit.io import atomic_write_text, read_json_file, to_json

from .model import BallScrewModel
from .physics import fin_parameter

FORMAT = "groupfit-ballscrew/1"
KIND = "ballscrew"


def model_to_dict(model: BallScrewModel, *, runs: dict[str, str] | None = None) -> dict[str, Any]:
    """The model file object of a fitted :class:`BallScrewModel`.

    ``h_W_m2K``, ``alpha_prime`` (the law in use, the line ``a0 + a1·τ0`` with
    the α′(t) table it was fitted to, and the table law's α′(t) curve) and,
    per source, ``C1`` and ``C2``; the screw's known constants and the
    identification settings so that the estimator can be rebuilt.
    """
    a0, a1 = model.alpha_prime_
    return {
        "format": FORMAT,
        "kind": KIND,
        "h_W_m2K": float(model.h_),
        "lambda_1_m": float(model.lambda_),
        "alpha_prime": {
            "used": model.alpha_law,
            "law": "a0_m2_s + a1_m2_sK * tau0_K",
            "a0_m2_s": float(a0),
            "a1_m2_sK": float(a1),
            "reference_x_m": float(model.reference_x_),
            "table": model.alpha_table_,
            "curve": {
                "law": "interpolated in log t, held beyond its ends",
                "t_s": [float(t) for t in model.alpha_curve_[0]],
                "alpha_prime_m2_s": [float(a) for a in model.alpha_curve_[1]],
            },
        },
        "source_offset_m": float(model.source_offset_),
        "sources": [{"name": name, **entry} for name, entry in model.sources_.items()],
        "screw": {
            "diameter_m": float(model.diameter),
            "conductivity_W_mK": float(model.conductivity),
            "expansion_1_K": float(model.expansion),
        },
        "settings": {
            "alpha_law": model.alpha_law,
            "source_offset": model.source_offset,
            "transient_fraction": float(model.transient_fraction),
            "alpha_step_s": float(model.alpha_step_s),
            "identification_time_s": float(model.identification_time_s),
            "smooth_s": float(model.smooth_s),
            "steady_window_s": float(model.steady_window_s),
        },
        "identification": {**model.identification_, "runs": runs or {}},
    }


def save_model(model_dict: dict[str, Any], path: str | Path) -> None:
    atomic_write_text(path, to_json(model_dict))


def is_screw_file(path: str | Path) -> bool:
    """Whether ``path`` is a readable ball-screw model file (anything else: False, for its own loader to judge)."""
    try:
        data = read_json_file(path)
    except InputError:
        return False
    return isinstance(data, dict) and data.get("kind") == KIND


def load_model(path: str | Path) -> BallScrewModel:
    """Read a ball-screw model file and rebuild the fitted estimator."""
    path = Path(path)
    data = read_json_file(path)
    return checked_model(data, str(path))


def checked_model(data: Any, label: str) -> BallScrewModel:
    """The estimator of a model file's JSON object, or one line naming ``label`` and what is wrong."""
    if not isinstance(data, dict) or data.get("kind") != KIND:
        raise InputError(f"{label}: not a ball-screw model file (kind '{KIND}'); make one with groupfit screw identify")
    problem = model_problem(data)
    if problem is not None:
        raise InputError(f"{label}: invalid ball-screw model: {problem}")
    try:
        return model_from_dict(data)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{label}: ball-screw model file is incomplete or damaged ({exc!r})") from None


POSITIVE = (
    ("h_W_m2K",),
    ("lambda_1_m",),
    ("screw", "diameter_m"),
    ("screw", "conductivity_W_mK"),
    ("screw", "expansion_1_K"),
    ("settings", "transient_fraction"),
    ("settings", "identification_time_s"),
)
"""Physical parameters of the model file that must be finite and positive."""
MAX_ALPHA_M2_S = 1.0
"""Largest α′ a model file may hold (m²/s): steel's diffusivity is about 1e-5; a larger value is a corrupt file."""
FINITE = (("alpha_prime", "a0_m2_s"), ("alpha_prime", "a1_m2_sK"), ("alpha_prime", "reference_x_m"))


def _value(data: dict[str, Any], keys: tuple[str, ...]):
    for key in keys:
        if not isinstance(data, dict) or key not in data:
            return None
        data = data[key]
    return data


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def model_problem(data: dict[str, Any]) -> str | None:
    """The first thing wrong with a ball-screw model file's values (naming the key), or None."""
    for keys in POSITIVE + FINITE:
        value = _value(data, keys)
        if not _number(value) or (keys in POSITIVE and value <= 0):
            kind = "a positive number" if keys in POSITIVE else "a finite number"
            return f"{'.'.join(keys)} = {value!r}: must be {kind}"
    screw = data["screw"]
    lam = fin_parameter(data["h_W_m2K"], screw["conductivity_W_mK"], screw["diameter_m"] / 2.0)
    if not math.isclose(data["lambda_1_m"], lam, rel_tol=1e-9):
        return f"lambda_1_m = {data['lambda_1_m']!r}: not √(2h/(k·R0)) = {lam:.12g} of the file's h, k and diameter"
    offset = data.get("source_offset_m")
    if not _number(offset) or not 0 <= offset < 1:
        return f"source_offset_m = {offset!r}: must lie in [0, 1) m"
    if not 0 < data["settings"]["transient_fraction"] < 1:
        return f"settings.transient_fraction = {data['settings']['transient_fraction']!r}: must lie in (0, 1)"
    curve = _value(data, ("alpha_prime", "curve"))
    if curve is not None:
        for key, high in (("t_s", 1e9), ("alpha_prime_m2_s", MAX_ALPHA_M2_S)):
            values = curve.get(key) if isinstance(curve, dict) else None
            if not isinstance(values, list) or not all(_number(v) and 0 < v <= high for v in values):
                return f"alpha_prime.curve.{key}: must be a list of numbers in (0, {high:g}]"
    sources = data.get("sources")
    if not isinstance(sources, list) or not sources:
        return "sources: must list one or more heat sources"
    for k, entry in enumerate(sources):
        if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
            return f"sources[{k}]: must be an object with a name"
        if not all(_number(entry.get(c)) and abs(entry[c]) <= 1e6 for c in ("C1", "C2")):
            return f"sources[{k}] ({entry['name']}): C1 and C2 must be finite numbers of magnitude at most 1e6"
    return None


def model_from_dict(data: dict[str, Any]) -> BallScrewModel:
    settings, screw, alpha = dict(data["settings"]), data["screw"], data["alpha_prime"]
    curve = alpha.get("curve")
    settings.setdefault("alpha_law", "table" if curve else "line")
    model = BallScrewModel(
        diameter=float(screw["diameter_m"]),
        conductivity=float(screw["conductivity_W_mK"]),
        expansion=float(screw["expansion_1_K"]),
        **settings,
    )
    model.h_ = float(data["h_W_m2K"])
    model.lambda_ = float(data["lambda_1_m"])
    model.alpha_prime_ = (float(alpha["a0_m2_s"]), float(alpha["a1_m2_sK"]))
    model.alpha_table_ = list(alpha.get("table", []))
    if curve:
        times = np.asarray(curve["t_s"], dtype=float)
        alphas = np.asarray(curve["alpha_prime_m2_s"], dtype=float)
        finite = np.all(np.isfinite(times)) and np.all(np.isfinite(alphas))
        if (
            times.shape != alphas.shape
            or not times.size
            or not finite
            or np.any(np.diff(times) <= 0)
            or np.any(alphas <= 0)
        ):
            raise ValueError("alpha_prime.curve: t_s must increase and alpha_prime_m2_s be positive, one per time")
        model.alpha_curve_ = (times, alphas)
    elif settings["alpha_law"] == "table":
        raise ValueError("alpha law 'table' without alpha_prime.curve")
    model.reference_x_ = float(alpha["reference_x_m"])
    model.source_offset_ = float(data["source_offset_m"])
    model.sources_ = {}
    for entry in data["sources"]:
        entry = dict(entry)
        name = entry.pop("name")
        if not all(math.isfinite(float(entry[k])) for k in ("C1", "C2")):
            raise ValueError(f"source {name}: C1 and C2 must be finite")
        model.sources_[name] = entry
    ident = dict(data.get("identification", {}))
    ident.pop("runs", None)
    model.identification_ = ident
    return model
