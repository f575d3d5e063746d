"""The deployable physics AR(1) model: its model file, run-time routine, exports and command-line verbs.

:mod:`groupfit.models.ar1` is the estimator; this package turns it into a
model file (``"kind": "ar1"``, :mod:`.modelfile`) that ``replay`` runs
(:mod:`.rule`) and ``export`` writes as C, Structured Text and JSON
(:mod:`.export`).
"""
