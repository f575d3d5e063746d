"""Structured Text pieces of the rule's optional terms: the reference temperature, the position terms and
the dead band, and how the block reads a model input.

:func:`groupfit.export.st.render_st` fills its template with these.
"""

from __future__ import annotations

from groupfit.runtime import FAULT_POSITION, RuleTables


def input_value(tables: RuleTables, j: int) -> str:
    """The expression of model input ``j`` (0-based) in the block."""
    r = tables.input_reading[j]
    return reading_value(tables, r + 1) if r >= 0 else f"derivedValue[{tables.input_derived[j] + 1}]"


# --------------------------------------------------------------------- reference temperature


def reading_value(tables: RuleTables, number: int | str) -> str:
    """Measured reading ``number`` (1-based, or a constant's name) as the model takes it: minus the reference."""
    if tables.reference_reading >= 0:
        return f"(lastGood[{number}] - lastGood[{tables.reference_reading + 1}])"
    if tables.reference_start:
        return f"(lastGood[{number}] - firstGood[{number}])"
    return f"lastGood[{number}]"


def reference_pieces(tables: RuleTables, real: str) -> dict[str, str]:
    """The block's pieces for the model's reference temperature (only ``criterion_value`` without one)."""
    pieces = {"criterion_value": reading_value(tables, "CRITERION"), "reference_vars": ""}
    pieces.update(reset_reference="", step_reference="")
    if not tables.reference_start:
        return pieces
    n_temps = tables.n_temps
    pieces["reference_vars"] = (
        f"    firstGood : ARRAY[1..{n_temps}] OF {real};\n"
        f"    hasFirst : ARRAY[1..{n_temps}] OF BOOL := [{', '.join(['FALSE'] * n_temps)}];\n"
    )
    pieces["reset_reference"] = (
        "    FOR m := 1 TO N_TEMPS DO\n        firstGood[m] := 0.0;\n        hasFirst[m] := FALSE;\n    END_FOR;\n"
    )
    pieces["step_reference"] = (
        "    (* reference: every measured sensor's first good reading since Reset *)\n"
        f"    FOR m := 1 TO {tables.n_measured} DO\n"
        "        IF NOT hasFirst[m] THEN\n"
        "            IF badCount[m] = 0 THEN\n"
        "                firstGood[m] := lastGood[m];\n"
        "                hasFirst[m] := TRUE;\n"
        "            END_IF;\n"
        "        END_IF;\n"
        "    END_FOR;\n"
    )
    return pieces


# --------------------------------------------------------------------- axis position and dead band


def position_pieces(tables: RuleTables, real: str, literal) -> dict[str, str]:
    """The block's pieces of a position model and a dead band (all empty without them).

    The position terms are written out as the dot product is: per power k of
    ``d = P - P0`` one array per term, indexed by group (``PCOEF_k_0`` the
    constant, ``PCOEF_k_m`` the coefficient of model input m), evaluated by
    Horner's scheme from the highest power, as the other targets do.
    """
    pieces = dict(position_vars="", position_constants="", reset_position="", position_terms="")
    pieces.update(dead_band="", position_fault="")
    if tables.has_position:
        order = tables.position_order
        pieces["position_vars"] = (
            "    positionMm : $real;\n    positionD : $real;\n    positionPoly : $real;\n"
            "    positionTerm : $real;\n    positionClamped : BOOL;\n"
            "    K0Um : $real; (* K0(T), um: SD43900 takes -K0Um / 1000 *)\n"
            "    SlopeUmPerMm : $real; (* c1(T) = tan(beta), um/mm: SD43910 takes -SlopeUmPerMm / 1000 *)\n"
        ).replace("$real", real)
        lines = [
            f"    POSITION : INT := {tables.position_reading + 1}; (* Temps[POSITION]: axis position, mm *)",
            f"    P0 : {real} := {literal(tables.p0_mm)};",
            f"    TRAVEL_MIN : {real} := {literal(tables.travel_min_mm)};",
            f"    TRAVEL_MAX : {real} := {literal(tables.travel_max_mm)};",
            "    (* Position terms: PCOEF_k_0 the constant of c_k (um/mm^k), PCOEF_k_m its coefficient of input m. *)",
        ]
        for k in range(order):
            for j in range(tables.n_inputs + 1):
                values = ", ".join(literal(v) for v in tables.position_coefficients[:, k, j])
                lines.append(f"    PCOEF_{k + 1}_{j} : ARRAY[1..{tables.n_groups}] OF {real} := [{values}];")
        pieces["position_constants"] = "\n".join(lines) + "\n"
        pieces["reset_position"] = "    K0Um := 0.0;\n    SlopeUmPerMm := 0.0;\n"
        terms = [
            "",
            "        (* position: P clamped to the travel, d = P - P0, Horner from the highest power *)",
            "        positionClamped := FALSE;",
            "        positionMm := lastGood[POSITION];",
            "        IF positionMm < TRAVEL_MIN THEN",
            "            positionMm := TRAVEL_MIN;",
            "            positionClamped := TRUE;",
            "        END_IF;",
            "        IF positionMm > TRAVEL_MAX THEN",
            "            positionMm := TRAVEL_MAX;",
            "            positionClamped := TRUE;",
            "        END_IF;",
            "        positionD := positionMm - P0;",
        ]
        for k in range(order, 0, -1):
            terms.append(f"        positionTerm := PCOEF_{k}_0[currentGroup];")
            for j in range(tables.n_inputs):
                term = f"PCOEF_{k}_{j + 1}[currentGroup] * {input_value(tables, j)}"
                terms.append(f"        positionTerm := positionTerm + {term};")
            if k == order:
                terms.append("        positionPoly := positionTerm;")
            else:
                terms.append("        positionPoly := positionPoly * positionD + positionTerm;")
        terms += [
            "        SlopeUmPerMm := positionTerm;",
            "        K0Um := prediction;",
            "        prediction := prediction + positionPoly * positionD;",
        ]
        pieces["position_terms"] = "\n".join(terms)
        pieces["position_fault"] = "    IF NOT faulted THEN\n        IF positionClamped THEN\n"
        pieces["position_fault"] += f"            Fault := Fault + {FAULT_POSITION};\n        END_IF;\n    END_IF;\n"
    if tables.has_dead_band:
        pieces["position_vars"] += f"    bandTarget : {real} := 0.0;\n    bandOutside : BOOL;\n"
        pieces["position_constants"] += (
            f"    DEAD_BAND_REF : INT := {tables.dead_band_reading + 1};\n"
            f"    DEAD_BAND : {real} := {literal(tables.dead_band_c)}; (* degC *)\n"
        )
        pieces["reset_position"] += "    bandTarget := 0.0;\n"
        pieces["dead_band"] = (
            "        (* dead band: keep the last target while every measured input is near the reference *)\n"
            "        bandOutside := FALSE;\n"
            f"        FOR m := 1 TO {tables.n_measured} DO\n"
            "            difference := lastGood[m] - lastGood[DEAD_BAND_REF];\n"
            "            IF ABS(difference) > DEAD_BAND THEN\n"
            "                bandOutside := TRUE;\n"
            "            END_IF;\n"
            "        END_FOR;\n"
            "        IF bandOutside THEN\n"
            "            bandTarget := target;\n"
            "        ELSE\n"
            "            target := bandTarget;\n"
            "        END_IF;\n"
        )
    return pieces
