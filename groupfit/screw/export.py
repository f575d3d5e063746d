"""The ball-screw model's run-time law exported: C99 (``c``) and the law's numbers (``json``).

The C routine ``gfs_error_um(t_s, x_m, tau0_K, &error_um)`` performs the
operations of :meth:`groupfit.screw.deploy.ScrewLaw.step` in the same order,
with the tables written as exact literals, so its results equal the Python
replay bit for bit (C library ``exp``, ``log``, ``erfc``, ``sqrt``; no
fused multiply-add). Structured Text is refused: IEC 61131-3 has no error
function among its standard functions, and the law needs erfc.
"""

from __future__ import annotations

import json

from groupfit.errors import InputError
from groupfit.export.literals import double_literal
from groupfit.screw.deploy import FAULT_READING, ScrewLaw
from groupfit.screw.physics import ALPHA_FLOOR

SCREW_TARGETS = ("c", "json")
REFUSED = {
    "st": "IEC 61131-3 Structured Text has no error function (erfc) among its standard functions, and the "
    "ball-screw law integrates erfc over the screw; export c or json and call it from the PLC",
    "sheet": "the controller sheet maps a grouped model's offset onto setting data; the ball-screw law is a "
    "function of time and position with no such settings; export c or json",
    "table": "the position table holds the powers of a position polynomial; the ball-screw law is no polynomial",
    "cec": "a CEC table is one curve over the position; the ball-screw error changes with time since the source "
    "came on; export c or json",
}


def check_screw_target(target: str) -> None:
    """InputError naming why ``target`` cannot take a ball-screw law (nothing for ``c`` and ``json``)."""
    if target not in SCREW_TARGETS:
        reason = REFUSED.get(target, f"choose one of {', '.join(SCREW_TARGETS)}")
        raise InputError(f"export --target {target} of a ball-screw model: {reason}")


def render_screw(law: ScrewLaw, target: str) -> dict[str, str]:
    """``{file name: text}`` of ``target`` for one source's law, or InputError naming why it cannot be."""
    check_screw_target(target)
    if target == "c":
        return {"groupfit_screw.h": header_text(law), "groupfit_screw.c": source_text(law)}
    return {"groupfit_screw_runtime.json": json.dumps(law.to_json(), indent=1) + "\n"}


def header_text(law: ScrewLaw) -> str:
    return f"""/* groupfit_screw.h - ball-screw thermal error of source {law.source} (groupfit, docs/ballscrew.md). */
#ifndef GROUPFIT_SCREW_H
#define GROUPFIT_SCREW_H

#define GFS_LINE_LAW {1 if law.law == "line" else 0}
#define GFS_FAULT_READING ({FAULT_READING})

/* E (um) at x_m (m from the source) t_s seconds after the source came on; tau0_K is the rise at the
 * reference sensor (used by the line law only). Returns 0, or GFS_FAULT_READING (error_um = 0). */
int gfs_error_um(double t_s, double x_m, double tau0_K, double *error_um);

#endif
"""


def _array(name: str, values) -> str:
    body = ",\n".join("    " + double_literal(v) for v in values)
    return f"static const double {name}[{len(values)}] = {{\n{body}\n}};\n"


def source_text(law: ScrewLaw) -> str:
    """The C99 source of the law (module docstring)."""
    constants = {
        "GFS_C1": law.c1,
        "GFS_C2": law.c2,
        "GFS_LAMBDA": law.lam,
        "GFS_X0": law.x0,
        "GFS_EXPANSION": law.expansion,
        "GFS_FLOOR": ALPHA_FLOOR,
    }
    if law.law == "line":
        constants.update(GFS_A0=law.a0, GFS_A1=law.a1)
    lines = [
        f"/* groupfit_screw.c - ball-screw thermal error of source {law.source}, alpha law '{law.law}'. */",
        "#include <math.h>",
        '#include "groupfit_screw.h"',
        "",
        *(f"static const double {name} = {double_literal(value)};" for name, value in constants.items()),
        "",
        f"#define GFS_N_NODES {len(law.u)}",
        _array("GFS_U", law.u),
        _array("GFS_W", law.w),
    ]
    if law.law == "line":
        alpha = """static double gfs_alpha(double t, double tau0)
{
    double alpha = GFS_A0 + GFS_A1 * tau0;
    (void)t;
    return alpha < GFS_FLOOR ? GFS_FLOOR : alpha;
}
"""
    else:
        lines += [f"#define GFS_N_TABLE {len(law.log_t)}", _array("GFS_LN_T", law.log_t)]
        lines += [_array("GFS_LN_ALPHA", law.log_alpha)]
        alpha = """static double gfs_alpha(double t, double tau0)
{
    double lt = log(t);
    double slope;
    int j = 0;
    (void)tau0;
    if (lt <= GFS_LN_T[0]) {
        return exp(GFS_LN_ALPHA[0]);
    }
    if (lt >= GFS_LN_T[GFS_N_TABLE - 1]) {
        return exp(GFS_LN_ALPHA[GFS_N_TABLE - 1]);
    }
    while (lt > GFS_LN_T[j + 1]) {
        j++;
    }
    slope = (GFS_LN_ALPHA[j + 1] - GFS_LN_ALPHA[j]) / (GFS_LN_T[j + 1] - GFS_LN_T[j]);
    return exp(GFS_LN_ALPHA[j] + slope * (lt - GFS_LN_T[j]));
}
"""
    tau_check = " || !isfinite(tau0_K)" if law.law == "line" else ""
    lines += [
        alpha,
        f"""int gfs_error_um(double t_s, double x_m, double tau0_K, double *error_um)
{{
    double alpha;
    double scale;
    double total = 0.0;
    int k;
    *error_um = 0.0;
    if (!(isfinite(t_s) && isfinite(x_m) && x_m >= 0.0){tau_check}) {{
        return GFS_FAULT_READING;
    }}
    if (t_s <= 0.0) {{
        return 0;
    }}
    alpha = gfs_alpha(t_s, tau0_K);
    if (alpha < GFS_FLOOR) {{
        alpha = GFS_FLOOR;
    }}
    scale = 2.0 * sqrt(alpha * t_s);
    for (k = 0; k < GFS_N_NODES; k++) {{
        double xi = x_m * GFS_U[k];
        double gamma = (GFS_C1 * exp(-GFS_LAMBDA * xi) + GFS_C2 * exp(GFS_LAMBDA * xi)) * erfc((xi + GFS_X0) / scale);
        total = total + gamma * GFS_W[k];
    }}
    *error_um = 1e6 * GFS_EXPANSION * x_m * total;
    return 0;
}}
""",
    ]
    return "\n".join(lines)


__all__ = ["REFUSED", "SCREW_TARGETS", "check_screw_target", "render_screw"]
