"""C pieces of the rule's optional terms: the reference temperature, the position terms and the dead band.

:func:`groupfit.export.c.render_c` fills its templates with these; each
returns the template fields of its term (empty strings for a model without it).
"""

from __future__ import annotations

from groupfit.export.literals import c_comment_text as _ascii
from groupfit.export.literals import real_literal
from groupfit.runtime import FAULT_POSITION, RuleTables


def reference_header(tables: RuleTables) -> dict[str, str]:
    """Header pieces of the model's reference temperature (empty without one)."""
    macros = fields = ""
    if tables.reference_reading >= 0:
        macros = (
            f"#define GF_REFERENCE {tables.reference_reading} "
            f"/* temps[GF_REFERENCE] ({_ascii(tables.reference)}): every measured input is taken minus it */\n"
        )
    elif tables.reference_start:
        macros = "#define GF_REFERENCE_START 1 /* every measured input is taken minus its first good reading */\n"
        fields = (
            "    gf_real first[GF_N_TEMPS];  /* reference: first good reading per sensor since gf_init */\n"
            "    int has_first[GF_N_TEMPS];  /* 1 once first[] holds it */\n"
        )
    return {"reference_macros": macros, "reference_fields": fields}


def reference_source(tables: RuleTables) -> dict[str, str]:
    """Source pieces: ``GF_VALUE(m)``, a measured reading as the model takes it, and the start reference's state."""
    init = step = ""
    if tables.reference_reading >= 0:
        value = (
            "/* A measured reading as the model takes it: its last good value minus the reference's. */\n"
            "#define GF_VALUE(m) (s->last[m] - s->last[GF_REFERENCE])\n"
        )
    elif tables.reference_start:
        value = (
            "/* A measured reading as the model takes it: its last good value minus its first good reading. */\n"
            "#define GF_VALUE(m) (s->last[m] - s->first[m])\n"
        )
        init = "    for (m = 0; m < GF_N_TEMPS; m++) {\n        s->first[m] = 0;\n        s->has_first[m] = 0;\n    }\n"
        step = (
            "\n    /* reference: keep every measured sensor's first good reading */\n"
            f"    for (m = 0; m < {tables.n_measured}; m++) {{\n"
            "        if (!s->has_first[m] && s->bad[m] == 0) {\n"
            "            s->first[m] = s->last[m];\n"
            "            s->has_first[m] = 1;\n"
            "        }\n"
            "    }\n"
        )
    else:
        value = "/* A measured reading as the model takes it: its last good value. */\n"
        value += "#define GF_VALUE(m) (s->last[m])\n"
    return {"reference_value": "\n" + value, "init_reference": init, "step_reference": step}


# --------------------------------------------------------------------- axis position and dead band


def position_header(tables: RuleTables) -> dict[str, str]:
    """Header pieces of a position model and a dead band (empty without them)."""
    macros = fields = ""
    if tables.has_position:
        macros += (
            f"#define GF_POSITION {tables.position_reading} "
            f"/* temps[GF_POSITION] ({_ascii(tables.position_name)}): axis position, mm */\n"
            f"#define GF_POSITION_ORDER {tables.position_order} /* highest power of (P - P0) */\n"
            f"#define GF_FAULT_POSITION {FAULT_POSITION} /* position outside the travel, clamped (output valid) */\n"
        )
        fields += (
            "    gf_real k0_um;              /* K0(T), um: the position-free part (SD43900 takes -k0_um / 1000) */\n"
            "    gf_real slope_um_per_mm;    /* c1(T) = tan(beta), um/mm (SD43910 takes -slope / 1000) */\n"
        )
    if tables.has_dead_band:
        macros += (
            f"#define GF_DEAD_BAND_REF {tables.dead_band_reading} "
            "/* dead band: no update while every measured input is within GF_DEAD_BAND_C of it */\n"
        )
        fields += "    gf_real band_target;        /* dead band: the last target computed outside it */\n"
    return {"position_macros": macros, "position_fields": fields}


def position_source(tables: RuleTables) -> dict[str, str]:
    """Source pieces: the position polynomial after the dot product, the dead band after the target."""
    pieces = dict(position_constants="", init_position="", position_locals="", position_terms="")
    pieces.update(dead_band="", position_fault="")
    constants = []
    if tables.has_position:
        order = tables.position_order
        rows = []
        for g, group in enumerate(tables.position_coefficients):
            powers = ", ".join("{ " + ", ".join(real_literal(v) for v in row) + " }" for row in group)
            rows.append(f"    /* group {g + 1} */ {{ {powers} }}")
        constants += [
            "/* Position terms: per group, per power k = 1..GF_POSITION_ORDER of d = P - P0, the coefficient\n"
            " * c_k(T): constant, then one per model input (um per mm^k, um per mm^k and unit). */\n",
            "static const gf_real gf_position_coef[GF_N_GROUPS][GF_POSITION_ORDER][GF_N_INPUTS + 1] = {\n"
            + ",\n".join(rows)
            + "\n};\n",
            f"static const gf_real gf_p0 = {real_literal(tables.p0_mm)}; /* P0, mm */\n",
            f"static const gf_real gf_travel_min = {real_literal(tables.travel_min_mm)}; /* modelled travel, mm */\n",
            f"static const gf_real gf_travel_max = {real_literal(tables.travel_max_mm)};\n",
        ]
        pieces["init_position"] = "    s->k0_um = 0;\n    s->slope_um_per_mm = 0;\n"
        pieces["position_locals"] = "    int clamped = 0;\n    int k;\n"
        value = "x[m]" if tables.derived else "GF_VALUE(m)"
        pieces["position_terms"] = (
            "\n        {\n"
            "            /* position: P clamped to the travel, d = P - P0, Horner from the highest power */\n"
            "            gf_real position = s->last[GF_POSITION];\n"
            "            gf_real d;\n"
            "            gf_real poly = 0;\n"
            "            if (position < gf_travel_min) {\n"
            "                position = gf_travel_min;\n"
            "                clamped = 1;\n"
            "            }\n"
            "            if (position > gf_travel_max) {\n"
            "                position = gf_travel_max;\n"
            "                clamped = 1;\n"
            "            }\n"
            "            d = position - gf_p0;\n"
            "            for (k = GF_POSITION_ORDER - 1; k >= 0; k--) {\n"
            "                const gf_real *prow = gf_position_coef[s->group - 1][k];\n"
            "                gf_real term = prow[0];\n"
            "                for (m = 0; m < GF_N_INPUTS; m++) {\n"
            f"                    term = term + prow[m + 1] * {value};\n"
            "                }\n"
            "                if (k == GF_POSITION_ORDER - 1) {\n"
            "                    poly = term;\n"
            "                } else {\n"
            "                    poly = poly * d + term;\n"
            "                }\n"
            "                if (k == 0) {\n"
            "                    s->slope_um_per_mm = term;\n"
            "                }\n"
            "            }\n"
            "            s->k0_um = prediction;\n"
            "            prediction = prediction + poly * d;\n"
            "        }"
        )
        pieces["position_fault"] = " + (clamped ? GF_FAULT_POSITION : 0)"
        if order < 1:
            raise ValueError("a position model has order >= 1")
    if tables.has_dead_band:
        constants.append(f"static const gf_real gf_dead_band = {real_literal(tables.dead_band_c)}; /* degC */\n")
        pieces["init_position"] += "    s->band_target = 0;\n"
        pieces["dead_band"] = (
            "        {\n"
            "            /* dead band: keep the last target while every measured input is near the reference */\n"
            "            int outside = 0;\n"
            f"            for (m = 0; m < {tables.n_measured}; m++) {{\n"
            "                gf_real difference = s->last[m] - s->last[GF_DEAD_BAND_REF];\n"
            "                if (difference < 0) {\n"
            "                    difference = -difference;\n"
            "                }\n"
            "                if (difference > gf_dead_band) {\n"
            "                    outside = 1;\n"
            "                }\n"
            "            }\n"
            "            if (outside) {\n"
            "                s->band_target = target;\n"
            "            } else {\n"
            "                target = s->band_target;\n"
            "            }\n"
            "        }\n"
        )
    if constants:
        pieces["position_constants"] = "\n" + "".join(constants)
    return pieces
