"""Controller sheet: how the rule's output maps onto a machine's compensation.

The rule hands the controller a compensation value ``C`` in µm: minus the
predicted thermal error, clamped and rate-limited. This module converts it to
the forms controllers take and writes a sheet (text and JSON) for the person
commissioning the machine:

* SINUMERIK temperature compensation, position-dependent form
  ``ΔK = K0 + tanβ·(P − P0)``: SD43900 ``TEMP_COMP_ABS_VALUE`` = K0 in mm,
  SD43910 ``TEMP_COMP_SLOPE`` = tanβ, SD43920 ``TEMP_COMP_REF_POSITION`` =
  P0 in mm, enabled by the bits of MD32750 ``TEMP_COMP_TYPE``; MD32760
  ``COMP_ADD_VELO_FACTOR`` spreads large changes over interpolation cycles.
* Integer offsets in fixed units (e.g. 0.1 µm per count, saturating at
  ±30 000 counts), as controllers with integer compensation registers take.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import ROUND_HALF_UP, Decimal

from groupfit.errors import InputError
from groupfit.export.reading_units import TEMPERATURE_UNIT, conversion_note, is_temperature_reading
from groupfit.export.sheet_probe import probe_lines, with_probe
from groupfit.io import to_json
from groupfit.runtime import FAULT_POSITION, RuleTables

UM_PER_MM = 1000.0

MD32750_BITS = {
    0: "position-independent temperature compensation (SD43900)",
    1: "position-dependent temperature compensation (SD43910, SD43920)",
    2: "temperature compensation in tool direction",
}


def sinumerik_abs_value_mm(compensation_um: float) -> float:
    """SD43900 TEMP_COMP_ABS_VALUE (K0, mm) for a compensation value in µm."""
    _require_finite(compensation_um)
    return float(compensation_um) / UM_PER_MM


def sinumerik_temp_comp_type(
    *, position_independent: bool = True, position_dependent: bool = False, tool_direction: bool = False
) -> int:
    """MD32750 TEMP_COMP_TYPE: bit 0, bit 1 and bit 2 as named."""
    return int(position_independent) | (int(position_dependent) << 1) | (int(tool_direction) << 2)


def sinumerik_total_um(k0_mm: float, slope: float, position_mm: float, ref_position_mm: float) -> float:
    """The compensation SINUMERIK applies at position P: ``K0 + tanβ·(P − P0)``, in µm."""
    return (k0_mm + slope * (position_mm - ref_position_mm)) * UM_PER_MM


MIN_RESOLUTION_UM = 1e-6
MAX_RESOLUTION_UM = 1e5
"""The µm one count of an integer register may stand for: a picometre to the largest plausible error."""
MAX_COUNTS = 2**31 - 1
"""The largest magnitude of an integer register (a signed 32-bit word)."""


@dataclass(frozen=True)
class IntegerForm:
    """A fixed-point compensation register: ``counts = C / resolution``, saturating.

    Attributes
    ----------
    resolution_um : float
        µm per count (0.1 for a register in 0.1 µm).
    limit : int
        Largest magnitude the register holds (30 000: ±3 mm at 0.1 µm).
    """

    resolution_um: float = 0.1
    limit: int = 30000

    def __post_init__(self):
        if not (math.isfinite(self.resolution_um) and MIN_RESOLUTION_UM <= self.resolution_um <= MAX_RESOLUTION_UM):
            raise InputError(
                f"integer resolution {self.resolution_um!r} µm: give the µm one count stands for, "
                f"{MIN_RESOLUTION_UM:g} to {MAX_RESOLUTION_UM:g}"
            )
        if int(self.limit) != self.limit or not 1 <= self.limit <= MAX_COUNTS:
            raise InputError(
                f"integer limit {self.limit!r}: the register's largest magnitude in counts, a whole number 1 to "
                f"{MAX_COUNTS} (a 32-bit register)"
            )

    def counts(self, compensation_um: float) -> int:
        """Counts for ``compensation_um``: nearest count, halves away from zero, saturated at ±limit.

        The division is done on the decimal values as written (0.25 µm at
        0.1 µm is exactly 2.5 counts, so 3), not on their binary approximations.
        """
        _require_finite(compensation_um)
        exact = Decimal(repr(float(compensation_um))) / Decimal(repr(float(self.resolution_um)))
        rounded = int(exact.quantize(Decimal(1), rounding=ROUND_HALF_UP))
        return max(-self.limit, min(self.limit, rounded))

    def um(self, counts: int) -> float:
        """The compensation in µm a register value stands for."""
        return float(Decimal(int(counts)) * Decimal(repr(float(self.resolution_um))))

    @property
    def range_um(self) -> float:
        """Largest magnitude (µm) the register holds."""
        return self.um(self.limit)


def _require_finite(value: float) -> None:
    if not math.isfinite(float(value)):
        raise ValueError(f"compensation value {value!r} is not a finite number")


def reading_list(tables: RuleTables) -> list[dict]:
    """Every reading the controller passes per sample, in order: name, unit, valid range, what it feeds."""
    readings = []
    for r, name in enumerate(tables.raw_names):
        temperature = is_temperature_reading(tables, r)
        convert = conversion_note(name) if temperature else None
        readings.append(
            {
                "index": r + 1,
                "name": name,
                "unit": TEMPERATURE_UNIT if temperature else f"as column '{name}' of the modelling data",
                **({"convert": convert} if convert else {}),
                "valid_min": tables.valid_min[r],
                "valid_max": tables.valid_max[r],
                "range_rule": {
                    "temperature": "switching.temp_min_c/temp_max_c of the model file (by default the "
                    "modelling range +-15 degC, rounded outward)",
                    "source": "switching.source_ranges of the model file (by default: a 0/1 signal [0, 1]; "
                    "otherwise the modelling range widened by max(span, largest magnitude / 2, 1), not below 0 "
                    "if it never was, rounded outward)",
                    "fallback": "not in the model file (older file): any number within +-1e9",
                    "position": "the axis position, mm: any finite number; outside the modelled travel it is "
                    "clamped to the travel and flagged",
                }[tables.valid_origin[r]],
                "criterion": r == tables.criterion_reading,
                "feeds": tables.uses_of(r),
            }
        )
    return readings


def controller_sheet(tables: RuleTables, integer: IntegerForm = IntegerForm()) -> dict:
    """The sheet as a JSON-ready object."""
    period = tables.sampling_period_s
    clamp_counts = [integer.counts(tables.comp_min_um), integer.counts(tables.comp_max_um)]
    output_counts = [integer.counts(tables.output_min_um), integer.counts(tables.output_max_um)]
    saturates = max(abs(tables.output_min_um), abs(tables.output_max_um)) > integer.range_um
    return {
        "format": "groupfit-controller-sheet/1",
        "readings": reading_list(tables),
        "derived_inputs": [
            {"name": d.name, "computed_as": d.describe(), "from_reading": d.reading + 1} for d in tables.derived
        ],
        "on_invalid_reading": f"NaN, +-inf or a value outside its valid range: the last good value stands in "
        f"for up to {tables.hold_samples} sample(s) (derived inputs keep being computed from it), then the "
        "output is the safe output (no compensation) until the reading is valid again",
        "output": {
            "name": "compensation",
            "unit": "um",
            "definition": "C = -(predicted thermal error), clamped to [comp_min_um, comp_max_um] (a probe "
            "check's correction may carry it on to [output_min_um, output_max_um]), then changed by at most "
            "rate_limit_um per sample",
            "sign": "the thermal error is the displacement the model was fitted on (positive along the "
            "axis as measured); C moves the axis the opposite way. If your error was measured with the "
            "opposite sign, write -C. Check the sign on the machine with a small test value first.",
            "comp_min_um": tables.comp_min_um,
            "comp_max_um": tables.comp_max_um,
            "output_min_um": tables.output_min_um,
            "output_max_um": tables.output_max_um,
            "rate_limit_um_per_sample": tables.rate_limit_um,
            "rate_limit_um_per_s": tables.rate_limit_um / period,
            "sampling_period_s": period,
            "on_sensor_fault": "C ramps to 0 at the rate limit (no compensation)",
        },
        "sinumerik": {
            "form": "dK = K0 + tanb * (P - P0)",
            "MD32750_TEMP_COMP_TYPE": sinumerik_temp_comp_type(),
            "MD32750_bits": {str(bit): text for bit, text in MD32750_BITS.items()},
            "MD32750_note": "bit 0 only: the grouped model is position-independent. Set bit 1 (value 3) "
            "only when a position-dependent slope is also written.",
            "SD43900_TEMP_COMP_ABS_VALUE": {"value": "C / 1000", "unit": "mm", "role": "K0"},
            "SD43910_TEMP_COMP_SLOPE": {"value": 0.0, "unit": "1 (tan beta)", "role": "tanb"},
            "SD43920_TEMP_COMP_REF_POSITION": {"value": 0.0, "unit": "mm", "role": "P0"},
            "writing": "the PLC writes SD43900 once per sample (every "
            f"{period:g} s) from the compensation block's output",
            "MD32760_COMP_ADD_VELO_FACTOR": "the NC traverses a change of the compensation over several "
            "interpolation cycles when it exceeds MD32760 x MD32000 MAX_AX_VELO per cycle; the rule's "
            f"rate limit already bounds each change to {tables.rate_limit_um:g} um per sample",
        },
        "integer": {
            "resolution_um": integer.resolution_um,
            "limit_counts": integer.limit,
            "range_um": integer.range_um,
            "counts": "round(C / resolution_um), halves away from zero, saturated at +-limit_counts",
            "clamp_counts": clamp_counts,
            "output_counts": output_counts,
            "rate_limit_counts_per_sample": integer.counts(tables.rate_limit_um),
            "clamp_exceeds_register": saturates,
        },
    }


def sheet_text(sheet: dict) -> str:
    """The sheet for a person: units, sign, registers, limits."""
    out, sin, integer = sheet["output"], sheet["sinumerik"], sheet["integer"]
    lines = [
        "groupfit controller sheet",
        "=========================",
        "",
        "Readings the controller passes every sample, in this order",
    ]
    for reading in sheet["readings"]:
        unit = f" {TEMPERATURE_UNIT}" if reading["unit"] == TEMPERATURE_UNIT else ""
        notes = (["switching criterion"] if reading["criterion"] else []) + reading["feeds"]
        notes += [reading["convert"]] if "convert" in reading else []
        lines.append(
            f"  {reading['index']:>2}. {reading['name']:<16} valid {reading['valid_min']:g} .. "
            f"{reading['valid_max']:g}{unit}   ({'; '.join(notes)})"
        )
    if any(r["unit"] != "degC" for r in sheet["readings"]):
        lines.append("  A source column is passed in the unit of its column in the modelling data (e.g. 0/1, r/min).")
    for derived in sheet["derived_inputs"]:
        lines.append(f"  derived input {derived['name']}: {derived['computed_as']}, by the routine itself")
    if "reference" in sheet:
        lines.append(f"  Reference temperature: {sheet['reference']['text']}.")
    if "on_position_outside_travel" in sheet:
        lines.append(f"  Axis position: {sheet['on_position_outside_travel']}.")
    if "dead_band" in sheet:
        lines.append(f"  Dead band: {sheet['dead_band']['text']}.")
    lines += [
        f"  Invalid reading: {sheet['on_invalid_reading']}.",
        "",
        "Output of the run-time rule",
        f"  C = -(predicted thermal error) in um, clamped to [{out['comp_min_um']:g}, {out['comp_max_um']:g}] um",
        f"  (probe checks may carry it on to [{out['output_min_um']:g}, {out['output_max_um']:g}] um),",
        f"  changed by at most {out['rate_limit_um_per_sample']:g} um per sample "
        f"({out['rate_limit_um_per_s']:.4g} um/s at {out['sampling_period_s']:g} s per sample).",
        f"  Sign: {out['sign']}",
        f"  Sensor fault: {out['on_sensor_fault']}.",
        "",
        "SINUMERIK temperature compensation (dK = K0 + tanb * (P - P0))",
        f"  MD32750 TEMP_COMP_TYPE          = {sin['MD32750_TEMP_COMP_TYPE']}"
        "   (bit 0 position-independent, bit 1 position-dependent, bit 2 tool direction)",
        *_sd_lines(sin),
        f"  {sin['writing']}.",
        f"  MD32760 COMP_ADD_VELO_FACTOR: {sin['MD32760_COMP_ADD_VELO_FACTOR']}.",
        "",
        f"Integer register ({integer['resolution_um']:g} um per count, +-{integer['limit_counts']} counts "
        f"= +-{integer['range_um']:g} um)",
        f"  counts = {integer['counts']}",
        f"  clamp in counts: [{integer['clamp_counts'][0]}, {integer['clamp_counts'][1]}]",
        *(
            [
                f"  output in counts (probe checks may carry it past the clamp): [{integer['output_counts'][0]}, "
                f"{integer['output_counts'][1]}]"
            ]
            if integer["output_counts"] != integer["clamp_counts"]
            else []
        ),
        f"  rate limit: {integer['rate_limit_counts_per_sample']} counts per sample",
    ]
    if integer["clamp_exceeds_register"]:
        lines.append(
            "  WARNING: the output's range (the clamp, widened by probe checks) exceeds the register; values "
            "beyond it saturate."
        )
    return "\n".join(lines + probe_lines(sheet)) + "\n"


def render_sheet(tables: RuleTables, resolution_um: float = 0.1, counts_limit: int = 30000) -> dict[str, str]:
    """``{"groupfit_sheet.txt": …, "groupfit_sheet.json": …}``."""
    sheet = with_reference(controller_sheet(tables, IntegerForm(resolution_um, counts_limit)), tables)
    sheet = with_probe(with_position(sheet, tables), tables)
    return {"groupfit_sheet.txt": sheet_text(sheet), "groupfit_sheet.json": to_json(sheet)}


def _sd_lines(sin: dict) -> list[str]:
    """The three setting-data lines: from the position terms of a position model, else C and zeros."""
    if "position" not in sin:
        return [
            "  SD43900 TEMP_COMP_ABS_VALUE     = C / 1000   [mm]   (K0)",
            "  SD43910 TEMP_COMP_SLOPE         = 0          [-]    (tanb: the model has no position term)",
            "  SD43920 TEMP_COMP_REF_POSITION  = 0          [mm]   (P0)",
        ]
    position = sin["position"]
    lines = [
        "  SD43900 TEMP_COMP_ABS_VALUE     = -K0Um / 1000          [mm]   (K0 of the compensation)",
        "  SD43910 TEMP_COMP_SLOPE         = -SlopeUmPerMm / 1000  [-]    (tanb of the compensation)",
        f"  SD43920 TEMP_COMP_REF_POSITION  = {position['P0_mm']:<20g}  [mm]   (P0)",
        f"  {position['note']}",
    ]
    if position["order"] > 1:
        lines.append(f"  {position['higher_powers']}")
    return lines


def with_position(sheet: dict, tables: RuleTables) -> dict:
    """The sheet of a position model (SD43900/43910/43920 from K0, tanb and P0) and of a dead band."""
    if not (tables.has_position or tables.has_dead_band):
        return sheet
    sheet = dict(sheet)
    if tables.has_position:
        sin = dict(sheet["sinumerik"])
        sin["MD32750_TEMP_COMP_TYPE"] = sinumerik_temp_comp_type(position_dependent=True)
        sin["MD32750_note"] = "bits 0 and 1 (value 3): the model is position-dependent"
        sin["SD43900_TEMP_COMP_ABS_VALUE"] = {"value": "-K0Um / 1000", "unit": "mm", "role": "K0"}
        sin["SD43910_TEMP_COMP_SLOPE"] = {"value": "-SlopeUmPerMm / 1000", "unit": "1 (tan beta)", "role": "tanb"}
        sin["SD43920_TEMP_COMP_REF_POSITION"] = {"value": tables.p0_mm, "unit": "mm", "role": "P0"}
        sin["writing"] = (
            f"the PLC writes SD43900 and SD43910 once per sample (every {tables.sampling_period_s:g} s) from the "
            "block's outputs K0Um and SlopeUmPerMm (C: s->k0_um, s->slope_um_per_mm); SD43920 once"
        )
        sin["position"] = {
            "reading": tables.position_reading + 1,
            "name": tables.position_name,
            "P0_mm": tables.p0_mm,
            "travel_mm": [tables.travel_min_mm, tables.travel_max_mm],
            "order": tables.position_order,
            "note": "K0Um and SlopeUmPerMm are the model's (error) terms; the compensation is their negative. "
            "The rule's own output C (clamp, rate limit, dead band) is the total at the position read; "
            "through SD43900/43910 the NC applies the terms itself and MD32760 limits the rate.",
            "higher_powers": "powers 2 and up of (P - P0) have no setting data: use C (the total at the "
            "position read) or the equidistant position table (export --target table) in a compensation table",
        }
        sheet["sinumerik"] = sin
        sheet["on_position_outside_travel"] = (
            f"a position outside [{tables.travel_min_mm:g}, {tables.travel_max_mm:g}] mm is clamped to the travel "
            f"and flagged (fault bit {FAULT_POSITION}); the output stays valid"
        )
    if tables.has_dead_band:
        sheet["dead_band"] = {
            "reference": tables.raw_names[tables.dead_band_reading],
            "threshold_c": tables.dead_band_c,
            "text": "no update of the compensation while every measured input is within "
            f"{tables.dead_band_c:g} degC of {tables.raw_names[tables.dead_band_reading]}",
        }
    return sheet


def with_reference(sheet: dict, tables: RuleTables) -> dict:
    """The sheet with the model's reference temperature, when it has one."""
    if tables.reference is None:
        return sheet
    if tables.reference_start:
        text = (
            "every measured input is taken minus its own first good reading since the routine was reset: "
            "reset it when the machine starts cold, at ambient"
        )
    else:
        text = (
            f"every measured input is taken minus reading {tables.reference_reading + 1} ({tables.reference}); "
            "an invalid reference is an invalid reading (held, then the safe output)"
        )
    return {**sheet, "reference": {"reference": tables.reference, "text": text}}
