"""Equidistant position tables (``export --target table``): a controller's interpolated table of a position model.

A polynomial position model (:mod:`groupfit.position`, docs/position.md) has
powers of ``d = P − P0`` a controller's SD43910 cannot take. This module
tabulates them at equidistant nodes over the modelled travel; the controller
interpolates each column linearly and forms ``E ≈ K0(T) + Σ_k c_k(T)·table_k(P)``.
The spacing is the coarsest that keeps the interpolation error within a stated
tolerance for every thermal state of the modelling run (seed 004's table
spacing ``l ≤ L/(N_max − 1)``), and the error reached is written with the table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from groupfit.controller_limits import check_st_name
from groupfit.errors import InputError
from groupfit.export.literals import shortest_literal
from groupfit.model import ModelFile

DEFAULT_TABLE_TOLERANCE_UM = 0.5
"""Largest interpolation error of an exported position table (µm) unless another is asked for."""


@dataclass(frozen=True)
class PositionTable:
    """An equidistant table of the position powers for a controller's interpolating table.

    ``values[i, k − 1] = (P_i − P0)^k`` at the nodes ``P_i = start + i·spacing``
    (mm); the controller interpolates each column linearly in P and forms
    ``E ≈ K0(T) + Σ_k c_k(T)·table_k(P)``. ``error_um`` is the largest
    interpolation error of that sum over the modelling run's thermal states
    (the coefficients ``c_k(T)`` of every check run) and the travel.
    """

    start_mm: float
    spacing_mm: float
    nodes_mm: np.ndarray
    values: np.ndarray
    tolerance_um: float
    error_um: float

    def interpolate(self, positions) -> np.ndarray:
        """(N, order): every column interpolated linearly at ``positions`` (clamped to the table)."""
        positions = np.clip(np.asarray(positions, dtype=float), self.nodes_mm[0], self.nodes_mm[-1])
        return np.column_stack(
            [np.interp(positions, self.nodes_mm, self.values[:, k]) for k in range(self.values.shape[1])]
        )


def position_coefficients(model: ModelFile, inputs, groups) -> np.ndarray:
    """(N, order): ``c_1(T) … c_order(T)`` of every row."""
    rows = model.position.coefficient_array(intercept=model.intercept)[np.asarray(groups)]
    return rows[:, :, 0] + np.einsum("ikj,ij->ik", rows[:, :, 1:], np.asarray(inputs, dtype=float))


def curvature_bound(model: ModelFile, coefficients: np.ndarray, grid: np.ndarray) -> float:
    """Largest ``|∂²E/∂P²|`` over the thermal states (rows of ``coefficients``) and the positions ``grid``."""
    d = grid - model.position.p0_mm
    second = np.zeros((len(coefficients), len(d)))
    for k in range(2, coefficients.shape[1] + 1):
        second += coefficients[:, k - 1 : k] * (k * (k - 1)) * d[None, :] ** (k - 2)
    return float(np.max(np.abs(second))) if second.size else 0.0


def position_table(
    model: ModelFile, states: np.ndarray, tolerance_um: float = DEFAULT_TABLE_TOLERANCE_UM, max_nodes: int = 1025
) -> PositionTable:
    """The coarsest equidistant table whose interpolation error stays within ``tolerance_um``.

    ``states``: (S, order) coefficients ``c_k(T)`` of the thermal states to
    cover (:func:`position_coefficients` of the modelling run). Linear
    interpolation errs by at most ``h²/8·max|E''|`` on a spacing ``h``; the
    spacing is the travel divided into the fewest equal parts meeting that
    bound (seed 004: ``l ≤ L/(Nmax − 1)`` with at most ``max_nodes`` nodes),
    and the error is then measured on 64 points per table interval (and
    the table refined until it meets the tolerance there).
    """
    if model.position is None:
        raise InputError("the model has no position terms: no position table")
    if not (math.isfinite(tolerance_um) and tolerance_um > 0):
        raise InputError(f"table tolerance {tolerance_um!r} µm: must be a number > 0")
    low, high = model.position.travel_mm
    length = high - low
    fine = np.linspace(low, high, 4001)
    bound = curvature_bound(model, states, fine)
    parts = 1 if bound == 0 else max(1, math.ceil(length / math.sqrt(8.0 * tolerance_um / bound)))
    while True:
        if parts + 1 > max_nodes:
            raise InputError(
                f"a table within {tolerance_um:g} µm needs more than {max_nodes} nodes; raise the tolerance"
            )
        nodes = np.linspace(low, high, parts + 1)
        d = nodes - model.position.p0_mm
        values = np.column_stack([d**k for k in range(1, model.position.order + 1)])
        table = PositionTable(low, length / parts, nodes, values, tolerance_um, 0.0)
        error = table_error(model, table, states, np.linspace(low, high, 64 * parts + 1))
        if error <= tolerance_um:
            return replace(table, error_um=error)
        parts += max(1, parts // 8)


def table_error(model: ModelFile, table: PositionTable, states: np.ndarray, positions) -> float:
    """Largest ``|Σ_k c_k·(table_k(P) − d^k)|`` over the states and positions (µm)."""
    positions = np.asarray(positions, dtype=float)
    d = positions - model.position.p0_mm
    exact = np.column_stack([d**k for k in range(1, model.position.order + 1)])
    difference = table.interpolate(positions) - exact
    return float(np.max(np.abs(np.asarray(states) @ difference.T)))


def range_states(model: ModelFile) -> np.ndarray:
    """(2^order, order): the corners of the model's ``coefficient_ranges``.

    The interpolation error ``Σ_k c_k·δ_k(P)`` is linear in the ``c_k``, so
    its largest magnitude over the box of the modelling run's ranges is at a
    corner: a table within the tolerance at the corners is within it for
    every thermal state of that box.
    """
    ranges = model.position.coefficient_ranges
    if ranges is None:
        raise InputError("the model file holds no position.coefficient_ranges (refit it) to size a table")
    grids = np.meshgrid(*[np.asarray(r, dtype=float) for r in ranges], indexing="ij")
    return np.column_stack([g.ravel() for g in grids])


def render_table(
    model: ModelFile, tolerance_um: float = DEFAULT_TABLE_TOLERANCE_UM, name: str = "FB_GroupfitComp", real="LREAL"
) -> dict[str, str]:
    """The export target ``table``: the position table of a position model, sized for ``tolerance_um``."""
    if model.position is None:
        raise InputError("export --target table: the model has no position terms (fit it with --position)")
    return table_files(position_table(model, range_states(model), tolerance_um), name, real)


def table_files(table: PositionTable, name: str, real: str = "LREAL") -> dict[str, str]:
    """The table as a C array, an ST array and a controller table file (CSV), ``{file name: text}``."""
    check_st_name(name)
    order = table.values.shape[1]
    n = len(table.nodes_mm)
    header = (
        f"equidistant position table: {n} nodes from {table.start_mm:.17g} mm every {table.spacing_mm:.17g} mm; "
        f"column k = (P - P0)^k, k = 1..{order}; interpolate linearly; "
        f"interpolation error {table.error_um:.3g} um (tolerance {table.tolerance_um:g} um)"
    )
    c_rows = ",\n".join("    { " + ", ".join(f"{v:.17g}" for v in row) + " }" for row in table.values)
    c_text = (
        f"/* groupfit_position_table.h - {header}. Generated by groupfit export; do not edit. */\n"
        "#ifndef GROUPFIT_POSITION_TABLE_H\n#define GROUPFIT_POSITION_TABLE_H\n"
        f"#define GF_TABLE_N {n}\n#define GF_TABLE_ORDER {order}\n"
        f"#define GF_TABLE_START_MM {table.start_mm:.17g}\n#define GF_TABLE_SPACING_MM {table.spacing_mm:.17g}\n"
        f"static const double gf_position_table[GF_TABLE_N][GF_TABLE_ORDER] = {{\n{c_rows}\n}};\n#endif\n"
    )
    single = real == "REAL"
    flat = ", ".join(shortest_literal(v, single=single) for v in table.values.T.ravel())
    st_text = (
        f"(* {name}_PositionTable: {header}. Generated by groupfit export; do not edit.\n"
        f"   TABLE[k, i]: power k, node i (P = TABLE_START_MM + (i - 1) * TABLE_SPACING_MM). *)\n"
        "VAR_GLOBAL CONSTANT\n"
        f"    TABLE_N : INT := {n};\n"
        f"    TABLE_START_MM : {real} := {shortest_literal(table.start_mm, single=single)};\n"
        f"    TABLE_SPACING_MM : {real} := {shortest_literal(table.spacing_mm, single=single)};\n"
        f"    TABLE : ARRAY[1..{order}, 1..{n}] OF {real} := [{flat}];\n"
        "END_VAR\n"
    )
    csv_lines = [f"# {header}", "position_mm," + ",".join(f"d{k}" for k in range(1, order + 1))]
    csv_lines += [f"{p:.17g}," + ",".join(f"{v:.17g}" for v in row) for p, row in zip(table.nodes_mm, table.values)]
    return {
        "groupfit_position_table.h": c_text,
        f"{name}_PositionTable.st": st_text,
        "groupfit_position_table.csv": "\n".join(csv_lines) + "\n",
    }


__all__ = [
    "DEFAULT_TABLE_TOLERANCE_UM",
    "PositionTable",
    "position_coefficients",
    "position_table",
    "range_states",
    "render_table",
    "table_error",
    "table_files",
]
