"""Headstock housing geometry: a structured hexahedral mesh with named boundaries.

Coordinates (metres): ``x`` across the housing (0 … width), ``y`` up from the
mounting face on the bed (0 … height), ``z`` along the spindle axis from the
rear face (z = 0) to the front face at the spindle nose (z = length). The spindle
bore is a cylinder of the bore radius around the line ``x = width/2``,
``y = axis_height``, through the whole length.

The cross-section is an O-grid: rays from the spindle axis join points on the
bore circle to points on the outer rectangle, so the bore surface nodes lie on
the true circle at every resolution and a uniform refinement also refines the
geometry. The section is extruded along z with planes at the bearing-seat edges
and at the front-seat mid-plane.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from skfem import MeshHex

# Boundary names used by the solvers.
MOUNT = "mount"
OUTER = "outer"
FRONT_SEAT = "front_seat"
REAR_SEAT = "rear_seat"
BORE_FREE = "bore_free"


@dataclass(frozen=True)
class HousingGeometry:
    """Dimensions of the headstock housing (metres).

    Defaults resemble a mid-size turning centre: a 0.40 m wide, 0.45 m high,
    0.50 m long housing, spindle axis 0.30 m above the bed, bore Ø 0.15 m;
    the front (nose-side) bearing seat spans z = 0.42…0.48 m, the rear seat
    z = 0.03…0.07 m.
    """

    width: float = 0.40
    height: float = 0.45
    length: float = 0.50
    axis_height: float = 0.30
    bore_diameter: float = 0.15
    front_seat: tuple[float, float] = (0.42, 0.48)
    rear_seat: tuple[float, float] = (0.03, 0.07)

    @property
    def bore_radius(self) -> float:
        return 0.5 * self.bore_diameter

    @property
    def axis_xy(self) -> tuple[float, float]:
        return 0.5 * self.width, self.axis_height

    @property
    def front_seat_mid_z(self) -> float:
        return 0.5 * (self.front_seat[0] + self.front_seat[1])

    def problems(self) -> list[str]:
        """Return messages for inconsistent dimensions (empty when valid)."""
        out = []
        r = self.bore_radius
        xc, yc = self.axis_xy
        if not (r < yc and yc + r < self.height and r < xc):
            out.append(
                "the bore must lie inside the housing cross-section "
                "(axis_height ± bore_diameter/2 within 0…height and "
                "bore_diameter < width)"
            )
        for name, (z0, z1) in (("front_seat_m", self.front_seat), ("rear_seat_m", self.rear_seat)):
            if not (0.0 <= z0 < z1 <= self.length):
                out.append(f"{name} must satisfy 0 <= start < end <= length_m")
        if self.rear_seat[1] > self.front_seat[0]:
            out.append("rear_seat_m must end before front_seat_m starts")
        return out


@dataclass(frozen=True)
class MeshResolution:
    """Mesh density of the O-grid.

    Parameters
    ----------
    circumferential
        Number of element columns around the bore.
    radial
        Number of element layers from the bore to the outer faces.
    axial_spacing
        Largest element length along the spindle axis (m).
    refinements
        Uniform refinements: each one doubles the circumferential and radial
        counts and halves the axial spacing.
    """

    circumferential: int = 48
    radial: int = 6
    axial_spacing: float = 0.035
    refinements: int = 0

    def effective(self) -> tuple[int, int, float]:
        factor = 2**self.refinements
        return (self.circumferential * factor, self.radial * factor, self.axial_spacing / factor)


@dataclass
class HousingMesh:
    """The meshed housing and the node sets the solvers need.

    Attributes
    ----------
    mesh
        ``MeshHex`` with boundaries ``mount``, ``outer``, ``front_seat``,
        ``rear_seat`` and ``bore_free``.
    geometry
        The dimensions it was built from.
    nose_nodes
        Bore-surface nodes in the front-seat mid-plane (the spindle axis at the
        nose is their weighted mean position).
    nose_weights
        Arc-length weights of ``nose_nodes`` (sum to one).
    """

    mesh: MeshHex
    geometry: HousingGeometry
    nose_nodes: np.ndarray
    nose_weights: np.ndarray

    @property
    def surface_nodes(self) -> np.ndarray:
        return np.sort(self.mesh.boundary_nodes())


def _side_points(corners: np.ndarray, centre: np.ndarray, counts: list[int]) -> np.ndarray:
    """Points on the rectangle, equally spaced in angle seen from the centre
    within each side, corners included (counterclockwise, last corner omitted)."""
    pts = []
    for side, n in enumerate(counts):
        a, b = corners[side], corners[(side + 1) % 4]
        ang_a = math.atan2(*(a - centre)[::-1])
        ang_b = math.atan2(*(b - centre)[::-1])
        if ang_b < ang_a:
            ang_b += 2 * math.pi
        for k in range(n):
            ang = ang_a + (ang_b - ang_a) * k / n
            direction = np.array([math.cos(ang), math.sin(ang)])
            # intersection of the ray with the line through a and b
            edge = b - a
            mat = np.column_stack([direction, -edge])
            dist, _ = np.linalg.solve(mat, a - centre)
            pts.append(centre + dist * direction)
    return np.array(pts)


def _cross_section(geo: HousingGeometry, n_circ: int, n_rad: int):
    """Node coordinates (n_rad + 1, n_circ, 2) of the O-grid section."""
    xc, yc = geo.axis_xy
    centre = np.array([xc, yc])
    corners = np.array([[0.0, 0.0], [geo.width, 0.0], [geo.width, geo.height], [0.0, geo.height]])
    spans = []
    for side in range(4):
        a, b = corners[side] - centre, corners[(side + 1) % 4] - centre
        ang = math.atan2(a[0] * b[1] - a[1] * b[0], a @ b)
        spans.append(ang % (2 * math.pi))
    counts = [max(2, round(n_circ * s / (2 * math.pi))) for s in spans]
    counts[int(np.argmax(counts))] += n_circ - sum(counts)
    outer = _side_points(corners, centre, counts)
    rel = outer - centre
    circle = centre + geo.bore_radius * rel / np.linalg.norm(rel, axis=1)[:, None]
    s = np.linspace(0.0, 1.0, n_rad + 1)
    return circle[None, :, :] + s[:, None, None] * (outer - circle)[None, :, :]


def _axial_planes(geo: HousingGeometry, spacing: float) -> np.ndarray:
    breaks = sorted({0.0, geo.length, *geo.rear_seat, *geo.front_seat, geo.front_seat_mid_z})
    planes = [0.0]
    for z0, z1 in zip(breaks[:-1], breaks[1:]):
        n = max(1, math.ceil((z1 - z0) / spacing - 1e-9))
        planes.extend(z0 + (z1 - z0) * np.arange(1, n + 1) / n)
    return np.array(planes)


def build_housing_mesh(geo: HousingGeometry, resolution: MeshResolution | None = None) -> HousingMesh:
    """Mesh the housing with hexahedra and mark its boundaries.

    Parameters
    ----------
    geo
        Housing dimensions.
    resolution
        Mesh density; the defaults of :class:`MeshResolution` when omitted.

    Returns
    -------
    HousingMesh
    """
    resolution = resolution or MeshResolution()
    n_circ, n_rad, dz = resolution.effective()
    section = _cross_section(geo, n_circ, n_rad)
    zs = _axial_planes(geo, dz)
    n_z = len(zs)
    per_plane = (n_rad + 1) * n_circ

    xy = section.reshape(-1, 2)
    points = np.vstack([np.tile(xy[:, 0], n_z), np.tile(xy[:, 1], n_z), np.repeat(zs, per_plane)])

    i, j, k = np.meshgrid(np.arange(n_circ), np.arange(n_rad), np.arange(n_z - 1), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()

    def node(ii, jj, kk):
        return kk * per_plane + jj * n_circ + ii % n_circ

    # local vertex order of skfem's MeshHex1 with (a, b, c) = (around, out, z)
    cells = np.vstack(
        [
            node(i, j, k),
            node(i, j, k + 1),
            node(i, j + 1, k),
            node(i + 1, j, k),
            node(i, j + 1, k + 1),
            node(i + 1, j, k + 1),
            node(i + 1, j + 1, k),
            node(i + 1, j + 1, k + 1),
        ]
    ).astype(np.int32)
    mesh = MeshHex(points, cells)

    xc, yc = geo.axis_xy
    r_bore = geo.bore_radius
    gap = 0.25 * float(np.min(np.linalg.norm(section[1] - section[0], axis=1)))
    tol = 1e-9 * max(geo.width, geo.height, geo.length)

    def on_bore(x):
        radius = np.hypot(x[0] - xc, x[1] - yc)
        return (radius < r_bore + gap) & (x[2] > tol) & (x[2] < geo.length - tol)

    def in_range(x, z_range):
        return (x[2] > z_range[0] - tol) & (x[2] < z_range[1] + tol)

    mesh = mesh.with_boundaries(
        {
            MOUNT: lambda x: np.abs(x[1]) < tol,
            FRONT_SEAT: lambda x: on_bore(x) & in_range(x, geo.front_seat),
            REAR_SEAT: lambda x: on_bore(x) & in_range(x, geo.rear_seat),
            BORE_FREE: lambda x: on_bore(x) & ~in_range(x, geo.front_seat) & ~in_range(x, geo.rear_seat),
            OUTER: lambda x: ~on_bore(x) & (np.abs(x[1]) >= tol),
        }
    )

    k_nose = int(np.argmin(np.abs(zs - geo.front_seat_mid_z)))
    ring = section[0]
    chord = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1)
    weights = 0.5 * (chord + np.roll(chord, 1))
    nose_nodes = node(np.arange(n_circ), 0, k_nose)
    return HousingMesh(mesh=mesh, geometry=geo, nose_nodes=nose_nodes, nose_weights=weights / weights.sum())


def points_inside(geo: HousingGeometry, points: np.ndarray) -> np.ndarray:
    """True for points (3, n) inside the housing material (bore excluded)."""
    xc, yc = geo.axis_xy
    eps = 1e-12
    return (
        (points[0] >= -eps)
        & (points[0] <= geo.width + eps)
        & (points[1] >= -eps)
        & (points[1] <= geo.height + eps)
        & (points[2] >= -eps)
        & (points[2] <= geo.length + eps)
        & (np.hypot(points[0] - xc, points[1] - yc) >= geo.bore_radius)
    )


def boundary_facets_in_box(mesh: MeshHex, box: np.ndarray) -> np.ndarray:
    """Boundary facets whose midpoints lie in ``box`` = [[x0, x1], [y0, y1], [z0, z1]]."""
    facets = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, facets]].mean(axis=1)
    tol = 1e-9
    inside = np.all((mid >= box[:, :1] - tol) & (mid <= box[:, 1:] + tol), axis=0)
    return facets[inside]
