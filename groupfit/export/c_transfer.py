"""C pieces of the bumpless transfer after a switch (docs/switching.md).

:func:`groupfit.export.c.render_c` fills its templates with these: the
transfer's length and state, its start at a switch, and the prediction: the
serving group's, plus ``blend / (B + 1)`` of the gap from the last output
before the switch to the new group's first prediction, both whole numbers
converted to ``gf_real`` exactly, so the weight is one correctly rounded
division in every build, as in the Python rule.
"""

from __future__ import annotations

from groupfit.runtime import RuleTables


def transfer_header(tables: RuleTables) -> dict[str, str]:
    """Header pieces: the transfer's length and its state fields."""
    return {
        "transfer_macro": (
            f"#define GF_BLEND_SAMPLES {tables.blend_samples} /* bumpless transfer after a switch, samples "
            "(0: a hard switch) */\n"
        ),
        "transfer_field": (
            "    int blend;                  /* samples of the bumpless transfer still to go */\n"
            "    int has_previous;           /* 1 when the last sample computed a prediction (no sensor fault) */\n"
            "    gf_real previous;           /* that prediction, um */\n"
            "    gf_real gap;                /* last output before the switch minus the new group's first, um */\n"
        ),
    }


def transfer_source(dot_product: str, position: dict[str, str], *, has_position: bool) -> dict[str, str]:
    """Source pieces; ``position`` (the position and dead-band pieces) with its terms after the dot product."""
    prediction = (
        dot_product + position["position_terms"] + "\n"
        "        if (s->switched && s->has_previous) {\n"
        "            /* bumpless transfer: the gap from the last output to the new group's prediction */\n"
        "            s->gap = s->previous - prediction;\n"
        "${probe_switch}"
        "        }\n"
        "        if (s->blend > 0) {\n"
        "            /* blend / (GF_BLEND_SAMPLES + 1) of the gap: it closes by one share per sample */\n"
        "            gf_real share = (gf_real)s->blend / (gf_real)(GF_BLEND_SAMPLES + 1) * s->gap;\n"
        "            prediction = prediction + share;\n"
        + (
            "            s->k0_um = s->k0_um + share; /* K0 + tan(beta) (P - P0) stays the prediction */\n"
            if has_position
            else ""
        )
        + "        }\n"
        "        s->previous = prediction;\n"
        "        s->has_previous = 1;"
    )
    return {
        **position,
        "position_terms": "",
        "prediction": prediction,
        "transfer_init": "    s->blend = 0;\n    s->has_previous = 0;\n    s->previous = 0;\n    s->gap = 0;\n",
        "transfer_start": "    if (s->switched) {\n        s->blend = GF_BLEND_SAMPLES;\n        s->gap = 0;\n    }\n",
        "transfer_end": "    if (faulted) {\n        s->has_previous = 0;\n    }\n"
        "    if (s->blend > 0) {\n        s->blend--;\n    }\n",
    }
