"""Structured Text pieces of the bumpless transfer after a switch (docs/switching.md).

:func:`transfer_pieces` fills the block's template: the state and constants
of the transfer, its start at a switch, and the prediction: the serving
group's, plus ``blendShare / BLEND_SPAN`` of the gap from the last output
before the switch to the new group's first prediction (the share is a real
number that counts whole calls, so the weight is the one division every
target performs).
"""

from __future__ import annotations

from groupfit.runtime import RuleTables


def transfer_pieces(tables: RuleTables, real: str, literal, dot_product: str, position: dict[str, str]) -> dict:
    """The template fields of the transfer, with the position pieces (their terms after the dot product)."""
    loop = "\n".join(
        [
            "        prediction := COEF_0[currentGroup];",
            dot_product + position["position_terms"],
            "        (* bumpless transfer: the gap from the last output to the new group's prediction *)",
            "        IF Switched <> 0 AND hasPrevious THEN",
            "            transferGap := previousPrediction - prediction;",
            "            rcGap2 := rcGap2 + transferGap * transferGap; (* widens the next probe check's gate *)",
            "        END_IF;",
            "        IF blendLeft > 0 THEN",
            "            transferShare := blendShare / BLEND_SPAN * transferGap;",
            "            prediction := prediction + transferShare;",
            *(["            K0Um := K0Um + transferShare;"] if tables.has_position else []),
            "        END_IF;",
            "        previousPrediction := prediction;",
            "        hasPrevious := TRUE;",
        ]
    )
    return {
        **position,
        "position_terms": "",
        "prediction": loop,
        "transfer_vars": (
            f"    blendLeft : INT := 0;\n    blendShare : {real} := 0.0;\n    hasPrevious : BOOL := FALSE;\n"
            f"    previousPrediction : {real} := 0.0;\n    transferGap : {real} := 0.0;\n"
            f"    transferShare : {real};\n"
        ),
        "transfer_constants": (
            "    (* Bumpless transfer: after a switch the prediction is the new group's plus the gap from the last\n"
            "       output before it, BLEND_SAMPLES / BLEND_SPAN of it at the switch, one share less each call. *)\n"
            f"    BLEND_SAMPLES : INT := {tables.blend_samples};\n"
            f"    BLEND_ONE : {real} := 1.0;\n"
            f"    BLEND_SHARES : {real} := {literal(float(tables.blend_samples))};\n"
            f"    BLEND_SPAN : {real} := {literal(float(tables.blend_samples + 1))};\n"
        ),
        "transfer_reset": (
            "    blendLeft := 0;\n    blendShare := 0.0;\n    hasPrevious := FALSE;\n"
            "    previousPrediction := 0.0;\n    transferGap := 0.0;\n"
        ),
        "transfer_start": (
            "    IF Switched <> 0 THEN\n        blendLeft := BLEND_SAMPLES;\n        blendShare := BLEND_SHARES;\n"
            "        transferGap := 0.0;\n    END_IF;\n"
        ),
        "transfer_end": (
            "    IF faulted THEN\n        hasPrevious := FALSE;\n    END_IF;\n"
            "    IF blendLeft > 0 THEN\n        blendLeft := blendLeft - 1;\n"
            "        blendShare := blendShare - BLEND_ONE;\n    END_IF;\n"
        ),
    }
