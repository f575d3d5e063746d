"""Close the loop on measured data: residual → missing effect → augmented model → error before/after."""

from groupfit.diagnose.loop import diagnose
from groupfit.diagnose.result import DiagnosisResult

__all__ = ["DiagnosisResult", "diagnose"]
