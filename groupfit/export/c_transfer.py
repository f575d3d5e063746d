"""C pieces of the bumpless transfer after a switch (docs/switching.md).

:func:`groupfit.export.c.render_c` fills its templates with these: the
transfer's length and state, its start at a switch, and the prediction,
computed for the old group and then the serving group while a transfer runs
and blended ``(B + 1 − blend) / (B + 1)`` of the way, both whole numbers
converted to ``gf_real`` exactly, so the weight is one correctly rounded
division in every build, as in the Python rule.
"""

from __future__ import annotations

import textwrap

from groupfit.runtime import RuleTables

OLD_POSITION = "                old_k0 = s->k0_um;\n                old_slope = s->slope_um_per_mm;\n"


def transfer_header(tables: RuleTables) -> dict[str, str]:
    """Header pieces: the transfer's length and its state field."""
    return {
        "transfer_macro": (
            f"#define GF_BLEND_SAMPLES {tables.blend_samples} /* bumpless transfer after a switch, samples "
            "(0: a hard switch) */\n"
        ),
        "transfer_field": "    int blend;                  /* samples of the bumpless transfer still to go */\n",
    }


def transfer_source(dot_product: str, position: dict[str, str], *, has_position: bool) -> dict[str, str]:
    """Source pieces; ``position`` (the position and dead-band pieces) with its terms moved into the group loop."""

    def in_loop(code: str) -> str:
        return textwrap.indent(code.replace("s->group - 1", "g - 1"), "    ")

    prediction = (
        "        gf_real old = 0;\n"
        + ("        gf_real old_k0 = 0;\n        gf_real old_slope = 0;\n" if has_position else "")
        + ""
        "        int g;\n"
        "        prediction = 0;\n"
        "        /* the old group's prediction first while a transfer runs, then the serving group's */\n"
        "        for (g = (s->blend > 0) ? s->group - 1 : s->group; g <= s->group; g++) {\n"
        + in_loop(dot_product)
        + in_loop(position["position_terms"])
        + "\n"
        "            if (g < s->group) {\n"
        "                old = prediction;\n"
        + (
            "                old_k0 = s->k0_um;\n                old_slope = s->slope_um_per_mm;\n"
            if has_position
            else ""
        )
        + "            }\n"
        "        }\n"
        "        if (s->blend > 0) {\n"
        "            /* bumpless transfer: (GF_BLEND_SAMPLES + 1 - blend) / (GF_BLEND_SAMPLES + 1) of the way */\n"
        "            gf_real weight = (gf_real)(GF_BLEND_SAMPLES + 1 - s->blend) / (gf_real)(GF_BLEND_SAMPLES + 1);\n"
        "            prediction = old + weight * (prediction - old);\n"
        + (
            "            s->k0_um = old_k0 + weight * (s->k0_um - old_k0);\n"
            "            s->slope_um_per_mm = old_slope + weight * (s->slope_um_per_mm - old_slope);\n"
            if has_position
            else ""
        )
        + "        }"
    )
    return {
        **position,
        "prediction": prediction,
        "transfer_init": "    s->blend = 0;\n",
        "transfer_start": "    if (s->switched) {\n        s->blend = GF_BLEND_SAMPLES;\n    }\n",
        "transfer_end": "    if (s->blend > 0) {\n        s->blend--;\n    }\n",
    }
