"""Structured Text pieces of the bumpless transfer after a switch (docs/switching.md).

:func:`transfer_pieces` fills the block's template: the state and constants
of the transfer, its start at a switch, and the prediction, computed for the
old group and then the serving group while a transfer runs, blended
``blendStep / BLEND_SPAN`` of the way (the counter is a real number that
counts whole calls, so the weight is the one division every target performs).
"""

from __future__ import annotations

from groupfit.runtime import RuleTables


def transfer_pieces(tables: RuleTables, real: str, literal, dot_product: str, position: dict[str, str]) -> dict:
    """The template fields of the transfer, with the position pieces (their terms moved into the group loop)."""
    loop = "\n".join(
        [
            "        (* the old group's prediction first while a transfer runs, then the serving group's *)",
            "        IF blendLeft > 0 THEN",
            "            gFirst := currentGroup - 1;",
            "        ELSE",
            "            gFirst := currentGroup;",
            "        END_IF;",
            "        FOR g := gFirst TO currentGroup DO",
            "        prediction := COEF_0[g];",
            dot_product.replace("[currentGroup]", "[g]") + position["position_terms"].replace("[currentGroup]", "[g]"),
            "        IF g < currentGroup THEN",
            "            oldPrediction := prediction;",
            *(["            oldK0 := K0Um;", "            oldSlope := SlopeUmPerMm;"] if tables.has_position else []),
            "        END_IF;",
            "        END_FOR;",
            "        IF blendLeft > 0 THEN",
            "            prediction := oldPrediction + blendStep / BLEND_SPAN * (prediction - oldPrediction);",
            *(
                [
                    "            K0Um := oldK0 + blendStep / BLEND_SPAN * (K0Um - oldK0);",
                    "            SlopeUmPerMm := oldSlope + blendStep / BLEND_SPAN * (SlopeUmPerMm - oldSlope);",
                ]
                if tables.has_position
                else []
            ),
            "        END_IF;",
        ]
    )
    return {
        **position,
        "position_terms": "",
        "prediction": loop,
        "transfer_vars": (
            f"    blendLeft : INT := 0;\n    blendStep : {real} := 0.0;\n    oldPrediction : {real};\n"
            "    g : INT;\n    gFirst : INT;\n"
            + (f"    oldK0 : {real};\n    oldSlope : {real};\n" if tables.has_position else "")
        ),
        "transfer_constants": (
            "    (* Bumpless transfer: after a switch the prediction moves from the old group's to the new group's\n"
            "       over BLEND_SAMPLES calls, blendStep / BLEND_SPAN of the way at the switch's blendStep-th call. *)\n"
            f"    BLEND_SAMPLES : INT := {tables.blend_samples};\n"
            f"    BLEND_ONE : {real} := 1.0;\n"
            f"    BLEND_SPAN : {real} := {literal(float(tables.blend_samples + 1))};\n"
        ),
        "transfer_reset": "    blendLeft := 0;\n    blendStep := 0.0;\n",
        "transfer_start": (
            "    IF Switched <> 0 THEN\n        blendLeft := BLEND_SAMPLES;\n        blendStep := 0.0;\n    END_IF;\n"
            "    IF blendLeft > 0 THEN\n        blendStep := blendStep + BLEND_ONE;\n    END_IF;\n"
        ),
        "transfer_end": "    IF blendLeft > 0 THEN\n        blendLeft := blendLeft - 1;\n    END_IF;\n",
    }
