"""The controller sheet's probe-check part: what a probe cycle passes and which setting datum it moves."""

from __future__ import annotations

from groupfit.runtime import RuleTables


def with_probe(sheet: dict, tables: RuleTables) -> dict:
    """The sheet with its ``probe_checks`` entry."""
    t = tables.recalibration
    what = "offset hold" if t.method == "hold" else "Kalman filter on " + " + ".join(t.terms)
    return {
        **sheet,
        "probe_checks": {
            "method": what,
            "call": "after the routine's step of the sample at which the probe touched the reference artefact: "
            "gf_probe(state, E) in C, Probe := TRUE with ProbeErrorUm := E in Structured Text",
            "measured_error_um": "E = the thermal error the probe measured, um: the deviation from the "
            "artefact's reference value minus the compensation C active at that moment (the deviation is E + C, C "
            "being -prediction): the error the model predicts, not the residual after compensation",
            "result": "1 applied, 0 rejected by the innovation gate (a gross reading: flagged, never applied), "
            "-1 ignored (sensor fault, held readings, or not a reading)",
            "setting_datum": "SD43900 TEMP_COMP_ABS_VALUE (the position-independent offset K0): the correction "
            "enters the prediction, so C and with it SD43900 move, within the rate limit and the clamp widened by "
            "the correction's bound "
            f"({t.rate_um:g} um per sample for the correction itself, bounded to +-{t.x_max[0]:g} um); "
            "SD43910 and SD43920 are not touched by a probe cycle",
        },
    }


def probe_lines(sheet: dict) -> list[str]:
    """The sheet's text lines of the probe checks."""
    probe = sheet.get("probe_checks")
    if probe is None:
        return []
    return [
        "",
        f"Probe checks ({probe['method']})",
        f"  Call: {probe['call']}.",
        f"  E: {probe['measured_error_um']}.",
        f"  Returns: {probe['result']}.",
        f"  Setting datum: {probe['setting_datum']}.",
    ]


__all__ = ["probe_lines", "with_probe"]
