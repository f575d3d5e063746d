"""What the diagnosis found and did, as frozen values; dictionaries only for ``diagnose --json``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from groupfit.diagnose.candidates import Candidate
from groupfit.diagnose.notes import Note
from groupfit.diagnose.policy import Refusal
from groupfit.diagnose.report import diagnosis_summary
from groupfit.heldout.records import OverfitCheck, RidgeSetting
from groupfit.model import ModelFile

Metrics = Mapping[str, float]
"""Error metrics of a residual (``rms_um``, ``max_um``, ``R_um``, …; :func:`groupfit.model.error_metrics`)."""


@dataclass(frozen=True)
class InputSelection:
    """How the model's inputs were re-selected before the diagnosis (``diagnose --select``)."""

    method: str
    """``"joint"`` (the measured inputs and the candidate effects chosen together) or a method of
    :data:`groupfit.heldout.selection.SELECTION_METHODS` (the inputs alone)."""
    inputs: tuple[str, ...]
    """The measured inputs kept."""
    of: int
    """How many measured inputs the model had."""
    folds: str
    """The held-out folds the choice was scored on, in words."""
    order: tuple[str, ...] | None = None
    """Every name chosen (inputs and effects), in the order chosen (a joint selection)."""
    nested_held_out_rms_um: float | None = None
    """Held-out RMS (µm) of the whole procedure: each fold predicted by a selection made without it."""

    def to_json(self) -> dict[str, object]:
        record: dict[str, object] = {"method": self.method, "inputs": list(self.inputs), "of": self.of}
        if self.order is not None:
            record["order"] = list(self.order)
        record["folds"] = self.folds
        if self.nested_held_out_rms_um is not None:
            record["nested_held_out_rms_um"] = self.nested_held_out_rms_um
        return record


@dataclass(frozen=True)
class Step:
    """One accepted effect and what it did on the held-out folds."""

    candidate: Candidate
    held_out_rms_before: float
    held_out_rms_after: float
    alternatives: tuple[Candidate, ...] = ()
    """Candidates of other columns that explain the held-out error as well (within one standard error)."""
    joint: bool = False
    """Chosen together with the inputs (``select_jointly``): scored against the inputs chosen before it."""

    def to_dict(self) -> dict[str, object]:
        return {
            **self.candidate.to_dict(),
            "held_out_rms_before_um": self.held_out_rms_before,
            "held_out_rms_after_um": self.held_out_rms_after,
            "alternatives": [c.to_dict() for c in self.alternatives],
            "joint": self.joint,
        }


@dataclass(frozen=True)
class Refused:
    """A candidate that scored well enough but failed the rule it faced."""

    candidate: Candidate
    refusal: Refusal

    @property
    def rule_id(self) -> str:
        return self.refusal.rule_id

    @property
    def reason(self) -> str:
        return self.refusal.reason

    def to_dict(self) -> dict[str, object]:
        return {**self.candidate.to_dict(), "reason": self.reason}


@dataclass(frozen=True)
class BranchOutcome:
    """The diagnosis from absolute readings against the one on rises, each with its effects
    (:func:`groupfit.diagnose.branch.absolute_branch`)."""

    effects: Mapping[str, list[str]]
    """The effects' names found on rises (``given``) and on absolute readings (``absolute``)."""
    held_out_rms_um: Mapping[str, float]
    """The held-out RMS of the two end models (``given``, ``absolute``)."""
    folds_improved: int
    score: float
    as_well_with_fewer_coefficients: bool
    reason: str | None
    """Why absolute readings were not taken; None when they were."""
    rule_id: str | None = None
    """The rule that refused them (:mod:`groupfit.diagnose.policy`); not written to ``--json``."""

    def to_dict(self) -> dict[str, object]:
        return {
            "effects": {key: list(names) for key, names in self.effects.items()},
            "held_out_rms_um": dict(self.held_out_rms_um),
            "folds_improved": self.folds_improved,
            "score": self.score,
            "as_well_with_fewer_coefficients": self.as_well_with_fewer_coefficients,
            "reason": self.reason,
        }


@dataclass(frozen=True)
class ReferenceCheck:
    """The check of the model's reference sensor against absolute readings (:mod:`groupfit.diagnose.reference`)."""

    reference: str
    dropped: bool
    """Whether the model was refitted on absolute readings."""
    after_effects: int
    """How many effects were in when the check was made."""
    held_out_rms_um: Mapping[str, float]
    """The held-out RMS of the model as given and on absolute readings (``given``, ``absolute``)."""
    folds_improved: int
    n_folds: int
    score: float
    as_one_group: bool
    """A grouped model judged with its groups as one."""
    reason: str | None
    """Why the reference was kept; None when it was dropped."""
    branch: BranchOutcome | None = None
    """The diagnosis from absolute readings, when the reference survived the diagnosis on rises."""
    rule_id: str | None = None
    """The rule that kept the reference (:mod:`groupfit.diagnose.policy`); None when it was dropped."""

    def to_dict(self) -> dict[str, object]:
        out = {
            "reference": self.reference,
            "dropped": self.dropped,
            "after_effects": self.after_effects,
            "held_out_rms_um": dict(self.held_out_rms_um),
            "folds_improved": self.folds_improved,
            "n_folds": self.n_folds,
            "score": self.score,
            "as_one_group": self.as_one_group,
            "reason": self.reason,
            "rule_id": self.rule_id,
        }
        return out if self.branch is None else {**out, "branch": self.branch.to_dict()}


@dataclass(frozen=True)
class RunMetrics:
    """One validation run's error metrics before and after."""

    name: str
    before: Metrics
    after: Metrics

    def to_dict(self) -> dict[str, object]:
        return {"name": self.name, "before": dict(self.before), "after": dict(self.after)}


@dataclass(frozen=True)
class DiagnosisResult:
    """What the diagnosis found and did."""

    candidates: list[Candidate]
    added: list[Candidate]
    before: Mapping[str, Metrics]
    after: Mapping[str, Metrics]
    model: ModelFile
    notes: tuple[Note, ...] = ()
    checks_before: Mapping[str, Metrics] = field(default_factory=dict)
    checks_after: Mapping[str, Metrics] = field(default_factory=dict)
    residuals_before: Mapping[str, np.ndarray] = field(default_factory=dict)
    residuals_after: Mapping[str, np.ndarray] = field(default_factory=dict)
    steps: tuple[Step, ...] = ()
    refused: tuple[Refused, ...] = ()
    folds: str = ""
    base_check: OverfitCheck | None = None
    run_names: Mapping[str, str] = field(default_factory=dict)
    """Names of the modelling run(s) (``"data"``) and the validation run(s) (``"validate"``)."""
    selection: InputSelection | None = None
    """How the inputs were re-selected before the diagnosis (``diagnose --select``), when they were."""
    ridge: RidgeSetting | None = None
    """The ridge penalty the model was refitted with before the diagnosis (``diagnose --ridge``), when it was."""
    reference: ReferenceCheck | None = None
    """The check of the model's reference sensor, when the model has one."""
    ambient: tuple[str, ...] = ()
    """Columns declared ambient temperatures (``diagnose --ambient``), whatever their names."""
    validation_runs: tuple[RunMetrics, ...] = ()
    """Each validation run on its own: its name and its error metrics before and after."""

    def summary(self) -> str:
        """The report, as ``groupfit diagnose`` prints it."""
        return diagnosis_summary(self)

    def notes_of(self, kind: str) -> list[str]:
        """The texts of the notes of one kind (:mod:`groupfit.diagnose.notes`)."""
        return [n.text for n in self.notes if n.kind == kind]

    def to_json(self, model_path: str | None = None) -> dict[str, object]:
        """The machine-readable result (``diagnose --json``); ``model`` is the model file to use."""
        return {
            "candidates": [c.to_dict() for c in self.candidates],
            "added": [c.to_dict() for c in self.added],
            "steps": [s.to_dict() for s in self.steps],
            "refused": [r.to_dict() for r in self.refused],
            "folds": self.folds,
            "base_model": self.base_check.to_json() if self.base_check is not None else {},
            "selection": None if self.selection is None else self.selection.to_json(),
            "ridge": self.ridge.to_json() if self.ridge is not None else None,
            "reference": None if self.reference is None else self.reference.to_dict(),
            "before": {**self.before, "validate": self.before.get("validate")},
            "after": {**self.after, "validate": self.after.get("validate")},
            "validation_runs": [r.to_dict() for r in self.validation_runs],
            "improved": self.improved,
            "checks": {"before": self.checks_before, "after": self.checks_after},
            "notes": [n.text for n in self.notes],
            "model": None if model_path is None else str(model_path),
        }

    @property
    def changed(self) -> bool:
        """Whether the model differs from the one given: an effect added, inputs re-selected, a ridge refit or its
        reference dropped."""
        dropped = self.reference is not None and self.reference.dropped
        return bool(self.added) or self.selection is not None or bool(self.ridge and self.ridge.alpha) or dropped

    @property
    def improved(self) -> bool | None:
        """Whether the validation runs got better, together and each one; None without one (or when the model
        was not changed)."""
        if "validate" not in self.before or not self.changed:
            return None
        together = self.after["validate"]["rms_um"] < self.before["validate"]["rms_um"]
        return together and not self.worse_runs

    @property
    def worse_runs(self) -> list[RunMetrics]:
        """The validation runs on which the changed model's RMS error is not lower (none when it is unchanged)."""
        if not self.changed:
            return []
        return [r for r in self.validation_runs if r.after["rms_um"] >= r.before["rms_um"]]
