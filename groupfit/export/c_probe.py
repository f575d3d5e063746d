"""C pieces of the recalibration from probe checks: ``gf_probe()`` and the filter's state and steps.

:func:`groupfit.export.c.render_c` fills its templates with :func:`probe_header`
and :func:`probe_source`; the operations are those of
:class:`groupfit.runtime.recalibration.Recalibrator`, in its order.
"""

from __future__ import annotations

from string import Template

from groupfit.export.bounds import clamp, rate_limited_step
from groupfit.export.literals import double_literal, real_literal
from groupfit.runtime import PROBE_APPLIED, PROBE_IGNORED, PROBE_REJECTED, RuleTables
from groupfit.runtime.recalibration import PROBE_LIMIT_UM

FIELDS = """    gf_real rc_x[3];            /* recalibration: offset (um), drift (um per sample), gain */
    gf_real rc_P[3][3];         /* their covariance */
    gf_real rc_applied_um;      /* correction in the prediction (um), rate-limited */
    gf_real rc_model_um;        /* what the model commanded at the last sample (um, within its clamp) */
    gf_real rc_command_um;      /* the same before the clamp (um) */
    int rc_usable;              /* 1 when a check may be compared with the last sample's prediction */
    int rc_rejected;            /* checks rejected by the gate in a row */
    int rc_significant;         /* 1 when the last applied check left a correction that stands out of its noise */
    gf_real rc_gap2;            /* squared gaps of the switches since the last check (um^2): widen its gate */
    gf_real rc_lim_min;         /* the model's clamp (um): GF_COMP_MIN_UM/GF_COMP_MAX_UM, widened by checks */
    gf_real rc_lim_max;
"""

DECLARATION = """
/*
 * Probe checks (docs/recalibration.md of groupfit): after gf_step() of the
 * sample at which the machine touched its reference artefact, call
 * gf_probe(s, e) with e the measured thermal error in um - the deviation the
 * probe saw minus the compensation then active (s->comp_um), i.e. the error the
 * model predicts, not the residual. It returns GF_PROBE_APPLIED, GF_PROBE_REJECTED
 * (the innovation gate: a gross reading, flagged and never applied) or
 * GF_PROBE_IGNORED (that sample was in a sensor fault or on held readings, or e is
 * not a number within +-GF_PROBE_LIMIT_UM). From the next gf_step() on, the
 * prediction includes the correction, and s->comp_um with it: within the
 * model's clamp [GF_COMP_MIN_UM, GF_COMP_MAX_UM], which an applied check widens
 * to 2|e| (the correction then takes what the widening changes in the model's
 * command, so the estimate stays at e), plus the correction, within
 * [GF_OUT_MIN_UM, GF_OUT_MAX_UM]. On a
 * SINUMERIK the correction moves the position-independent offset (SD43900) the
 * compensation already writes; no other datum changes.
 */
#define GF_PROBE_APPLIED $applied
#define GF_PROBE_REJECTED $rejected
#define GF_PROBE_IGNORED ($ignored)
#define GF_PROBE_LIMIT_UM $limit
int gf_probe(gf_state *s, double measured_error_um);
"""

CONSTANTS = """
/* Recalibration ($description): per sample process variance q, initial variance p0 (offset um^2,
 * drift (um/sample)^2, gain), drift decay phi, check variance r, gate^2, significance^2 (0: every correction
 * is applied), state bounds, rate of the correction. */
static const gf_real gf_rc_q[3] = { $q };
static const gf_real gf_rc_p0[3] = { $p0 };
static const gf_real gf_rc_max[3] = { $x_max };
static const gf_real gf_rc_phi = $phi;
static const gf_real gf_rc_r = $r;
static const gf_real gf_rc_gate2 = $gate2;
static const gf_real gf_rc_sig2 = $sig2;
static const gf_real gf_rc_rate = $rate;
#define GF_RC_CONFIRM_AFTER $confirm

static void gf_rc_reset_covariance(gf_state *s)
{
    int i, j;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) {
            s->rc_P[i][j] = (i == j) ? gf_rc_p0[i] : (gf_real)0;
        }
    }
}

/* P h and h' P for h = (1, 0, m), m the last sample's model prediction; returns S = h' P h + r. */
static gf_real gf_rc_projections(const gf_state *s, gf_real ph[3], gf_real hp[3])
{
    gf_real m = s->rc_model_um;
    int i;
    for (i = 0; i < 3; i++) {
        ph[i] = s->rc_P[i][0] + s->rc_P[i][2] * m;
        hp[i] = s->rc_P[0][i] + s->rc_P[2][i] * m;
    }
    return hp[0] + hp[2] * m + gf_rc_r;
}

static void gf_rc_reset(gf_state *s)
{
    int i;
    for (i = 0; i < 3; i++) {
        s->rc_x[i] = 0;
    }
    gf_rc_reset_covariance(s);
    s->rc_applied_um = 0;
    s->rc_model_um = 0;
    s->rc_command_um = 0;
    s->rc_usable = 0;
    s->rc_rejected = 0;
    s->rc_significant = 0;
    s->rc_gap2 = 0;
    s->rc_lim_min = GF_COMP_MIN_UM;
    s->rc_lim_max = GF_COMP_MAX_UM;
}

static void gf_rc_clamp(gf_state *s)
{
    int i;
    for (i = 0; i < 3; i++) {
$clamp    }
}

/* Time update of one sample: the drift moves the offset and decays; P = F P F' + Q. */
static void gf_rc_propagate(gf_state *s)
{
    gf_real a[3][3];
    int i, j;
    s->rc_x[0] = s->rc_x[0] + s->rc_x[1];
    s->rc_x[1] = gf_rc_phi * s->rc_x[1];
    for (j = 0; j < 3; j++) {
        a[0][j] = s->rc_P[0][j] + s->rc_P[1][j];
        a[1][j] = gf_rc_phi * s->rc_P[1][j];
        a[2][j] = s->rc_P[2][j];
    }
    for (i = 0; i < 3; i++) {
        s->rc_P[i][0] = a[i][0] + a[i][1];
        s->rc_P[i][1] = a[i][1] * gf_rc_phi;
        s->rc_P[i][2] = a[i][2];
        s->rc_P[i][i] = s->rc_P[i][i] + gf_rc_q[i];
    }
    gf_rc_clamp(s);
}

/* The correction of this sample after the model's prediction: towards offset + gain * prediction (0 while it
 * does not stand out of its noise), rate-limited. */
static gf_real gf_rc_correct(gf_state *s, gf_real model_um, int usable)
{
    gf_real target, delta;
    s->rc_model_um = model_um;
    s->rc_usable = usable;
    target = s->rc_x[0] + s->rc_x[2] * model_um;
    if (gf_rc_sig2 > 0 && !s->rc_significant) {
        target = 0;
    }
$rate_limited    return s->rc_applied_um;
}
"""

FUNCTION = """
static int gf_rc_check(gf_state *s, double measured_error_um)
{
    gf_real m = s->rc_model_um;
    gf_real nu, sv, gate, target, ph[3], hp[3], k[3];
    int i, j;
    if (!s->rc_usable || !(measured_error_um >= -GF_PROBE_LIMIT_UM && measured_error_um <= GF_PROBE_LIMIT_UM)) {
        return GF_PROBE_IGNORED;
    }
    nu = ((gf_real)measured_error_um - m) - (s->rc_x[0] + s->rc_x[2] * m);
    sv = gf_rc_projections(s, ph, hp);
    if (!(sv > 0)) {
        return GF_PROBE_IGNORED;
    }
    /* a switch since the last check moved the prediction by its gap: the gate widens by it */
    gate = sv + s->rc_gap2;
    if (gate < gf_rc_p0[0]) {
        gate = gf_rc_p0[0]; /* never narrower than a new run's offset */
    }
    s->rc_gap2 = 0;
    if (nu * nu > gf_rc_gate2 * gate) {
        if (s->rc_rejected < GF_RC_CONFIRM_AFTER) {
            s->rc_rejected++;
            return GF_PROBE_REJECTED;
        }
        /* the checks keep disagreeing: a real change, which the offset takes whole (as the hold does) */
        s->rc_rejected = 0;
        s->rc_x[0] = s->rc_x[0] + nu;
        gf_rc_reset_covariance(s);
        gf_rc_clamp(s);
        s->rc_significant = 1;
        return GF_PROBE_APPLIED;
    }
    s->rc_rejected = 0;
    for (i = 0; i < 3; i++) {
        k[i] = ph[i] / sv;
    }
    for (i = 0; i < 3; i++) {
        s->rc_x[i] = s->rc_x[i] + k[i] * nu;
        for (j = 0; j < 3; j++) {
            s->rc_P[i][j] = s->rc_P[i][j] - k[i] * hp[j];
        }
    }
    gf_rc_clamp(s);
    /* the correction stands out when it exceeds significance sigmas of its deviation after the check */
    target = s->rc_x[0] + s->rc_x[2] * m;
    (void)gf_rc_projections(s, ph, hp);
    s->rc_significant = target * target > gf_rc_sig2 * (hp[0] + hp[2] * m);
    return GF_PROBE_APPLIED;
}

int gf_probe(gf_state *s, double measured_error_um)
{
    int result = gf_rc_check(s, measured_error_um);
    if (result == GF_PROBE_APPLIED) {
        /* a measured error widens the model's clamp to twice its size, within the output's bounds */
        gf_real w = (gf_real)measured_error_um;
        if (w < 0) {
            w = -w;
        }
        w = w + w;
        if (w > s->rc_lim_max) {
            s->rc_lim_max = w < GF_OUT_MAX_UM ? w : GF_OUT_MAX_UM;
        }
        if (-w < s->rc_lim_min) {
            s->rc_lim_min = -w > GF_OUT_MIN_UM ? -w : GF_OUT_MIN_UM;
        }
        /* the model's command at the check under the widened clamp: the offset takes what it changed */
        w = -s->rc_command_um;
$command_clamp        w = -w;
        if (w != s->rc_model_um) {
            s->rc_x[0] = s->rc_x[0] + (1 + s->rc_x[2]) * (s->rc_model_um - w);
            gf_rc_clamp(s);
            s->rc_model_um = w;
            s->rc_significant = 1;
        }
    }
    return result;
}
"""


def _fill(template: str, values: dict) -> str:
    return Template(template).substitute(values)


def probe_header(tables: RuleTables) -> dict[str, str]:
    """Header pieces: the state's fields and, after the struct, the codes and ``gf_probe``'s declaration."""
    declaration = _fill(
        DECLARATION,
        {
            "applied": PROBE_APPLIED,
            "rejected": PROBE_REJECTED,
            "ignored": PROBE_IGNORED,
            "limit": double_literal(PROBE_LIMIT_UM),
        },
    )
    return {"probe_fields": FIELDS, "probe_declaration": declaration}


def probe_source(tables: RuleTables) -> dict[str, str]:
    """Source pieces: the constants and helpers, the calls in ``gf_init``/``gf_step``, and ``gf_probe``."""
    t = tables.recalibration
    constants = _fill(
        CONSTANTS,
        {
            "description": ", ".join(t.terms) + f" ({t.method})",
            "q": ", ".join(real_literal(v) for v in t.q),
            "p0": ", ".join(real_literal(v) for v in t.p0),
            "x_max": ", ".join(real_literal(v) for v in t.x_max),
            "phi": real_literal(t.phi),
            "r": real_literal(t.r),
            "gate2": real_literal(t.gate2),
            "sig2": real_literal(t.significance2),
            "rate": real_literal(t.rate_um),
            "confirm": t.confirm_after,
            "clamp": clamp("c", "s->rc_x[i]", "-gf_rc_max[i]", "gf_rc_max[i]", " " * 8),
            "rate_limited": rate_limited_step("c", "s->rc_applied_um", "target", "delta", "gf_rc_rate", " " * 4),
        },
    )
    return {
        "probe_constants": constants,
        "init_probe": "    gf_rc_reset(s);\n",
        "probe_propagate": "    gf_rc_propagate(s);\n",
        "probe_switch": "            s->rc_gap2 = s->rc_gap2 + s->gap * s->gap; /* widens the next check's gate */\n",
        "probe_invalidate": "        s->rc_usable = 0;\n",
        "probe_correct": (
            "        /* the correction from probe checks (0 until the first is applied) */\n"
            "        {\n"
            "            gf_real correction = gf_rc_correct(s, -target, !held); /* what the model commands */\n"
            "            prediction = prediction + correction;\n"
            "            target = target - correction;\n"
            "        }\n"
        ),
        "probe_command": "        s->rc_command_um = -target; /* what the model commands before its clamp */\n",
        "probe_function": _fill(
            FUNCTION,
            {
                "command_clamp": clamp("c", "w", "s->rc_lim_min", "s->rc_lim_max", " " * 8),
            },
        ),
    }


def with_probe(files: dict[str, str], tables: RuleTables) -> dict[str, str]:
    """The C files of :func:`groupfit.export.c.render_c` with their probe pieces filled in."""
    pieces = {**probe_header(tables), **probe_source(tables)}
    return {name: Template(text).safe_substitute(pieces) for name, text in files.items()}  # a "$" in a name stays


__all__ = ["probe_header", "probe_source", "with_probe"]
