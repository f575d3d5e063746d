"""Close the loop on measured data: residual → missing effect → augmented model → error before/after."""

from groupfit.diagnose.loop import DiagnosisResult, diagnose

__all__ = ["DiagnosisResult", "diagnose"]
