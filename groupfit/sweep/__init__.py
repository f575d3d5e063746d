"""Parameter sweeps: every combination of a study's settings, run once each.

A study is a TOML file (:mod:`groupfit.sweep.config`) that expands into run
specifications; each run (:mod:`groupfit.sweep.runs`) is a pure function of
its specification, run on local processes or a Dask cluster
(:mod:`groupfit.sweep.executors`), and its result is written to a SQLite study
database (:mod:`groupfit.sweep.store`) keyed by a hash of the specification,
so that a study started again runs only what is missing.
sensors are picked on held-out folds (:mod:`groupfit.heldout.selection`), :mod:`groupfit.sweep.report`
summarises a study in tables and figures, and :mod:`groupfit.sweep.study`
ties them together.
"""

from groupfit.sweep.config import RunSpec, Study, read_study
from groupfit.sweep.study import StudyOutcome, run_study

__all__ = ["RunSpec", "Study", "StudyOutcome", "read_study", "run_study"]
