"""The ball-screw model file (JSON, ``"format": "groupfit-ballscrew/1"``, ``"kind": "ballscrew"``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from groupfit.errors import InputError
from groupfit.io import atomic_write_text, read_json_file, to_json

from .model import BallScrewModel

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
    if not isinstance(data, dict) or data.get("kind") != KIND:
        raise InputError(f"{path}: not a ball-screw model file (kind '{KIND}'); make one with groupfit screw identify")
    try:
        return model_from_dict(data)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{path}: ball-screw model file is incomplete or damaged ({exc!r})") from None


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
        if times.shape != alphas.shape or not times.size or np.any(np.diff(times) <= 0) or np.any(alphas <= 0):
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
