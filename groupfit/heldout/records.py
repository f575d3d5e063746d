"""What a model's own held-out check reports: the over-fit check and the ridge penalty's choice, as frozen records.

They travel typed through ``fit`` and ``diagnose``; :meth:`to_json` gives the
``--json`` and report form at the edge.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple


@dataclass(frozen=True)
class OverfitCheck:
    """The model's in-sample RMS against its held-out RMS on the folds, and what to do when it over-fits."""

    in_sample_rms_um: float
    held_out_rms_um: float
    folds: str
    """How the folds were made (:meth:`groupfit.heldout.folds.Folds.describe`)."""
    overfitted: bool
    grouped: bool
    advice: str

    def to_json(self) -> dict[str, Any]:
        return {
            "in_sample_rms_um": self.in_sample_rms_um,
            "held_out_rms_um": self.held_out_rms_um,
            "folds": self.folds,
            "overfitted": self.overfitted,
            "grouped": self.grouped,
            "advice": self.advice,
        }


class RidgeScore(NamedTuple):
    """One penalty tried and its held-out RMS (µm)."""

    alpha: float
    held_out_rms_um: float


@dataclass(frozen=True)
class RidgeSetting:
    """The penalty of ``--ridge ALPHA|auto`` and how it was found.

    ``chosen``: ``"given"`` (the user's number) or ``"held-out"`` (the least
    error on held-out conditions or runs). ``held_out`` and ``folds``: every
    penalty tried with its held-out RMS, and the folds it was scored on (not
    for ``"given"``). ``default``: chosen without ``--ridge``, as ``fit`` does
    for a global model whose p it chose.
    """

    alpha: float
    chosen: str
    held_out: tuple[RidgeScore, ...] = ()
    folds: str = ""
    default: bool = False

    def to_json(self) -> dict[str, Any]:
        record: dict[str, Any] = {"alpha": self.alpha, "chosen": self.chosen}
        if self.chosen != "given":
            record["held_out"] = [score._asdict() for score in self.held_out]
            record["folds"] = self.folds
            record["default"] = self.default
        return record


__all__ = ["OverfitCheck", "RidgeScore", "RidgeSetting"]
