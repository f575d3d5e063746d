"""Structured Text pieces of the recalibration from probe checks: the inputs ``Probe``/``ProbeErrorUm``.

:func:`groupfit.export.st.render_st` fills its block with :func:`probe_pieces`.
A call with ``Probe = TRUE`` processes its sample, then folds the check
``ProbeErrorUm`` in, as ``gf_step`` followed by ``gf_probe`` does in C and
:class:`groupfit.runtime.recalibration.Recalibrator` in Python, operation for
operation.
"""

from __future__ import annotations

from string import Template
from textwrap import dedent, indent

from groupfit.export.bounds import clamp, rate_limited_step
from groupfit.runtime import PROBE_APPLIED, PROBE_IGNORED, PROBE_REJECTED, RuleTables
from groupfit.runtime.recalibration import PROBE_LIMIT_UM

PROBE_NONE = -2
"""``ProbeResult`` of a call without a check."""

DOC = """  Probe checks (docs/recalibration.md of groupfit):
    Probe         TRUE on the call of the sample at which the machine touched its reference:
                  after the sample, ProbeErrorUm (LREAL, um) - the measured thermal error, i.e. the
                  deviation the probe saw minus CompUm then active - corrects the prediction
                  from the next call on (it moves SD43900, the position-independent offset).
    ProbeResult   $applied applied, $rejected rejected by the innovation gate (flagged, never applied),
                  $ignored ignored (a sensor or period fault, held readings, no reading), $none no check.
"""

VARS = """    rcX : ARRAY[0..2] OF $real;
    rcP : ARRAY[0..2, 0..2] OF $real;
    rcA : ARRAY[0..2, 0..2] OF $real;
    rcPh : ARRAY[0..2] OF $real;
    rcHp : ARRAY[0..2] OF $real;
    rcK : ARRAY[0..2] OF $real;
    rcApplied : $real := 0.0;
    rcModel : $real := 0.0;
    rcCommand : $real := 0.0;
    rcDelta : $real;
    rcZ : $real;
    rcNu : $real;
    rcS : $real;
    rcGate : $real;
    rcGap2 : $real := 0.0;
    rcUsable : BOOL := FALSE;
    rcOutside : BOOL;
    rcRejected : INT := 0;
    rcSignificant : BOOL := FALSE;
    rcTarget : $real;
    rcLimMin : $real := $lim_min; (* the model's clamp, widened by checks *)
    rcLimMax : $real := $lim_max;
    rcW : $real;
    rcI : INT;
    rcJ : INT;
"""

CONSTANTS = """    (* Recalibration ($description): per-sample process variance, initial variance and bound of
       offset (um), drift (um per sample) and gain; drift decay; check variance; gate^2; significance^2
       (0: every correction is applied); rate (um per call). *)
    RC_Q : ARRAY[0..2] OF $real := [$q];
    RC_P0 : ARRAY[0..2] OF $real := [$p0];
    RC_MAX : ARRAY[0..2] OF $real := [$x_max];
    RC_PHI : $real := $phi;
    RC_R : $real := $r;
    RC_GATE2 : $real := $gate2;
    RC_SIG2 : $real := $sig2;
    RC_RATE : $real := $rate;
    RC_ZERO : $real := 0.0;
    RC_ONE : $real := 1.0;
    RC_CONFIRM : INT := $confirm;
    PROBE_LIMIT : LREAL := $limit;
"""

RESET = """    rcApplied := 0.0;
    rcLimMin := COMP_MIN;
    rcLimMax := COMP_MAX;
    rcModel := 0.0;
    rcCommand := 0.0;
    rcUsable := FALSE;
    rcRejected := 0;
    rcSignificant := FALSE;
    rcGap2 := 0.0;
    FOR rcI := 0 TO 2 DO
        rcX[rcI] := 0.0;
        FOR rcJ := 0 TO 2 DO
            rcP[rcI, rcJ] := 0.0;
        END_FOR;
        rcP[rcI, rcI] := RC_P0[rcI];
    END_FOR;
"""

CLAMP = clamp("st", "rcX[rcI]", "-RC_MAX[rcI]", "RC_MAX[rcI]", " " * 8)

PROPAGATE = """
    (* recalibration: time update (the drift moves the offset and decays; P := F P F' + Q) *)
    rcX[0] := rcX[0] + rcX[1];
    rcX[1] := RC_PHI * rcX[1];
    FOR rcJ := 0 TO 2 DO
        rcA[0, rcJ] := rcP[0, rcJ] + rcP[1, rcJ];
        rcA[1, rcJ] := RC_PHI * rcP[1, rcJ];
        rcA[2, rcJ] := rcP[2, rcJ];
    END_FOR;
    FOR rcI := 0 TO 2 DO
        rcP[rcI, 0] := rcA[rcI, 0] + rcA[rcI, 1];
        rcP[rcI, 1] := rcA[rcI, 1] * RC_PHI;
        rcP[rcI, 2] := rcA[rcI, 2];
        rcP[rcI, rcI] := rcP[rcI, rcI] + RC_Q[rcI];
$clamp    END_FOR;
"""

CORRECT = """        (* the correction from probe checks, towards offset + gain * prediction (0 while it does not
           stand out of its noise), rate-limited *)
        rcModel := -target; (* what the model commands, within its clamp *)
        rcUsable := NOT held;
        rcTarget := rcX[0] + rcX[2] * rcModel;
        IF RC_SIG2 > RC_ZERO AND NOT rcSignificant THEN
            rcTarget := RC_ZERO;
        END_IF;
$rate_limited        prediction := prediction + rcApplied;
        target := target - rcApplied;
"""

CHECK = """(* a probe check after this sample *)
ProbeResult := $none;
IF Probe THEN
    ProbeResult := $ignored;
    IF rcUsable AND ProbeErrorUm >= -PROBE_LIMIT AND ProbeErrorUm <= PROBE_LIMIT THEN
        rcZ := $to_real(ProbeErrorUm);
        rcNu := (rcZ - rcModel) - (rcX[0] + rcX[2] * rcModel);
$projections        rcOutside := rcS > RC_ZERO;
        IF rcOutside THEN
            (* a switch since the last check moved the prediction by its gap: the gate widens by it *)
            rcGate := rcS + rcGap2;
            IF rcGate < RC_P0[0] THEN
                rcGate := RC_P0[0]; (* never narrower than a new run's offset *)
            END_IF;
            rcGap2 := 0.0;
            rcOutside := rcNu * rcNu > RC_GATE2 * rcGate;
        END_IF;
        IF rcOutside AND rcRejected >= RC_CONFIRM THEN
            (* the checks keep disagreeing: a real change, which the offset takes whole (as the hold does) *)
            rcRejected := 0;
            rcX[0] := rcX[0] + rcNu;
            FOR rcI := 0 TO 2 DO
                FOR rcJ := 0 TO 2 DO
                    rcP[rcI, rcJ] := 0.0;
                END_FOR;
                rcP[rcI, rcI] := RC_P0[rcI];
$clamp            END_FOR;
            rcSignificant := TRUE;
            ProbeResult := $applied;
        ELSIF rcS > RC_ZERO THEN
            IF rcOutside THEN
                rcRejected := rcRejected + 1;
                ProbeResult := $rejected;
            ELSE
                rcRejected := 0;
                FOR rcI := 0 TO 2 DO
                    rcK[rcI] := rcPh[rcI] / rcS;
                END_FOR;
                FOR rcI := 0 TO 2 DO
                    rcX[rcI] := rcX[rcI] + rcK[rcI] * rcNu;
                    FOR rcJ := 0 TO 2 DO
                        rcP[rcI, rcJ] := rcP[rcI, rcJ] - rcK[rcI] * rcHp[rcJ];
                    END_FOR;
$clamp                END_FOR;
                (* the correction stands out when it exceeds significance sigmas of its deviation after the check *)
                rcTarget := rcX[0] + rcX[2] * rcModel;
$inner_projections                rcSignificant := rcTarget * rcTarget > RC_SIG2 * (rcHp[0] + rcHp[2] * rcModel);
                ProbeResult := $applied;
            END_IF;
        END_IF;
    END_IF;
    IF ProbeResult = $applied THEN
        (* a measured error widens the model's clamp to twice its size, within the output's bounds *)
        IF rcZ < RC_ZERO THEN
            rcW := -rcZ;
        ELSE
            rcW := rcZ;
        END_IF;
        rcW := rcW + rcW;
        IF rcW > rcLimMax THEN
            IF rcW < OUT_MAX THEN
                rcLimMax := rcW;
            ELSE
                rcLimMax := OUT_MAX;
            END_IF;
        END_IF;
        IF -rcW < rcLimMin THEN
            IF -rcW > OUT_MIN THEN
                rcLimMin := -rcW;
            ELSE
                rcLimMin := OUT_MIN;
            END_IF;
        END_IF;
        (* the model's command at the check under the widened clamp: the offset takes what it changed *)
        rcW := -rcCommand;
$command_clamp        rcW := -rcW;
        IF rcW <> rcModel THEN
            rcX[0] := rcX[0] + (RC_ONE + rcX[2]) * (rcModel - rcW);
            FOR rcI := 0 TO 2 DO
$outer_clamp            END_FOR;
            rcModel := rcW;
            rcSignificant := TRUE;
        END_IF;
    END_IF;
END_IF;
"""


PROJECTIONS = """        FOR rcI := 0 TO 2 DO
            rcPh[rcI] := rcP[rcI, 0] + rcP[rcI, 2] * rcModel;
            rcHp[rcI] := rcP[0, rcI] + rcP[2, rcI] * rcModel;
        END_FOR;
        rcS := rcHp[0] + rcHp[2] * rcModel + RC_R;
"""


def probe_pieces(tables: RuleTables, real: str, literal) -> dict[str, str]:
    """The block's probe inputs, output, state, constants and steps (``literal``: the block's real literals)."""
    t = tables.recalibration
    codes = {"applied": PROBE_APPLIED, "rejected": PROBE_REJECTED, "ignored": PROBE_IGNORED, "none": PROBE_NONE}
    constants = Template(CONSTANTS).substitute(
        real=real,
        description=", ".join(t.terms) + f" ({t.method})",
        q=", ".join(literal(v) for v in t.q),
        p0=", ".join(literal(v) for v in t.p0),
        x_max=", ".join(literal(v) for v in t.x_max),
        phi=literal(t.phi),
        r=literal(t.r),
        gate2=literal(t.gate2),
        sig2=literal(t.significance2),
        rate=literal(t.rate_um),
        confirm=t.confirm_after,
        limit=literal_double(PROBE_LIMIT_UM),
    )
    inner_clamp = indent(dedent(CLAMP), " " * 20)
    return {
        "probe_doc": Template(DOC).substitute(codes),
        "probe_inputs": "    Probe : BOOL;\n    ProbeErrorUm : LREAL;\n",
        "probe_outputs": "    ProbeResult : INT;\n",
        "probe_vars": Template(VARS).substitute(
            real=real, lim_min=literal(tables.comp_min_um), lim_max=literal(tables.comp_max_um)
        ),
        "probe_constants": constants,
        "reset_probe": RESET,
        "probe_period_fault": "    rcUsable := FALSE;\n",
        "probe_propagate": Template(PROPAGATE).substitute(clamp=CLAMP),
        "probe_invalidate": "        rcUsable := FALSE;\n",
        "probe_correct": Template(CORRECT).substitute(
            rate_limited=rate_limited_step("st", "rcApplied", "rcTarget", "rcDelta", "RC_RATE", " " * 8)
        ),
        "probe_command": "        rcCommand := -target; (* what the model commands before its clamp *)\n",
        "probe_check": Template(CHECK).substitute(
            codes,
            clamp=inner_clamp,
            command_clamp=clamp("st", "rcW", "rcLimMin", "rcLimMax", " " * 8),
            outer_clamp=indent(dedent(CLAMP), " " * 12),
            to_real=f"TO_{real}",
            projections=PROJECTIONS,
            inner_projections=indent(dedent(PROJECTIONS), " " * 16),
        ),
    }


def literal_double(value: float) -> str:
    """An LREAL literal with a decimal point."""
    text = repr(float(value))
    return text if "." in text or "e" in text else text + ".0"


__all__ = ["PROBE_NONE", "probe_pieces"]
