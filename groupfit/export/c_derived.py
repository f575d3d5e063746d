"""The C routine's derived inputs: their state fields, constants, start values and per-sample update.

:mod:`groupfit.export.c` places these pieces in its templates.
"""

from __future__ import annotations

from groupfit.export.literals import c_comment_text as _ascii
from groupfit.export.literals import double_literal, real_literal
from groupfit.runtime import RuleTables

TRANSFORM_NOTES = {
    "lowpass": "low-pass a = exp(-dt/tau), b = 1 - a.",
    "derivative": "3600 / dt (per hour).",
    "ontime": "dt / 3600 (hours per sample on).",
}
"""The comment above a transform's constants."""


def state_fields(tables: RuleTables) -> str:
    if not tables.derived:
        return ""
    fields = [
        "    int started[GF_N_DERIVED];  /* 1 once the source has had a good reading since gf_init */\n",
        "    gf_real derived[GF_N_DERIVED]; /* value of every derived input at the last sample */\n",
        "    gf_real memory[GF_N_DERIVED];  /* low-pass: its output; derivative: the last value; "
        "on-time: samples on */\n",
    ]
    for k, d in enumerate(tables.derived):
        if d.transform == "delay":
            fields.append(f"    gf_real line_{k}[GF_DELAY_{k}]; /* delay line of derived[{k}] */\n")
            fields.append(f"    int pos_{k};                 /* its oldest entry */\n")
    return "".join(fields)


def derived_constants(tables: RuleTables) -> str:
    lines = []
    for k, d in enumerate(tables.derived):
        if d.has_power:
            lines.append(
                f"/* derived[{k}], {_ascii(d.name)}: power stage (|x| / scale)^exponent, in double. The exponent\n"
                " * is volatile so that no compiler replaces pow() by multiplications (pow(x, 2.0) by x*x):\n"
                " * the C library's pow() is what every target computes. */\n"
            )
            lines.append(f"static const double gf_power_scale_{k} = {double_literal(d.power_scale)};\n")
            lines.append(f"static const volatile double gf_power_exponent_{k} = {double_literal(d.exponent)};\n")
        constants = d.transform_constants()
        if constants:
            lines.append(f"/* derived[{k}], {_ascii(d.name)}: {TRANSFORM_NOTES[d.transform]} */\n")
        lines += [f"static const gf_real gf_{name}_{k} = {real_literal(value)};\n" for name, value in constants]
    return ("\n" + "".join(lines)) if lines else ""


def init_derived(tables: RuleTables) -> str:
    lines = []
    for k, d in enumerate(tables.derived):
        lines.append(f"    s->started[{k}] = 0;\n    s->derived[{k}] = 0;\n    s->memory[{k}] = 0;\n")
        if d.transform == "delay":
            lines.append(f"    for (m = 0; m < GF_DELAY_{k}; m++) {{\n        s->line_{k}[m] = 0;\n    }}\n")
            lines.append(f"    s->pos_{k} = 0;\n")
    return "".join(lines)


def step_derived(tables: RuleTables) -> str:
    """The derived inputs' update, in the order of the other targets."""
    blocks = []
    for k, d in enumerate(tables.derived):
        r = d.reading
        v = f"s->last[{r}]"
        head = f"\n    /* derived[{k}] = {_ascii(d.name)}: {_ascii(d.describe())} (temps[{r}]) */\n"
        if d.has_power:
            head += (
                "    /* its power stage, in double precision in both builds, rounded to gf_real once */\n"
                f"    v = (gf_real)pow(fabs((double){v}) / gf_power_scale_{k}, gf_power_exponent_{k});\n"
            )
            v = "v"
        initial = "0" if d.from_rest else v
        if d.transform == "identity":
            blocks.append(head + f"    s->derived[{k}] = {v};\n")
            continue
        if d.transform == "delay":
            start = (
                f"        for (j = 0; j < GF_DELAY_{k}; j++) {{\n"
                f"            s->line_{k}[j] = {initial};\n"
                "        }\n"
                f"        s->pos_{k} = 0;\n"
            )
            update = (
                f"        s->derived[{k}] = s->line_{k}[s->pos_{k}];\n"
                f"        s->line_{k}[s->pos_{k}] = {v};\n"
                f"        s->pos_{k}++;\n"
                f"        if (s->pos_{k} >= GF_DELAY_{k}) {{\n"
                f"            s->pos_{k} = 0;\n"
                "        }\n"
            )
        else:
            start = f"        s->memory[{k}] = {initial};\n"
            if d.transform == "lowpass":
                update = (
                    f"        s->memory[{k}] = gf_lowpass_b_{k} * {v} + gf_lowpass_a_{k} * s->memory[{k}];\n"
                    f"        s->derived[{k}] = s->memory[{k}];\n"
                )
            elif d.transform == "ontime":
                update = (
                    f"        if ({v} != 0) {{\n"
                    f"            s->memory[{k}] = s->memory[{k}] + (gf_real)1;\n"
                    "        } else {\n"
                    f"            s->memory[{k}] = 0;\n"
                    "        }\n"
                    f"        s->derived[{k}] = {v} * (s->memory[{k}] * gf_ontime_step_{k});\n"
                )
            else:
                update = (
                    f"        s->derived[{k}] = ({v} - s->memory[{k}]) * gf_derivative_scale_{k};\n"
                    f"        s->memory[{k}] = {v};\n"
                )
        blocks.append(
            head
            + f"    if (!s->started[{k}] && s->bad[{r}] == 0) {{\n"
            + f"        s->started[{k}] = 1;\n"
            + start
            + "    }\n"
            + f"    if (s->started[{k}]) {{\n"
            + update
            + "    }\n"
        )
    return "".join(blocks)
