"""Section 4 (results), evaluation: how close the mesh is to its input and what the leaf measures.

- the paper's Table 1: distances from the boundary and the vein points to the mesh (section 5),
  and the mesh's facts (triangles, components, border loops, non-manifold edges, area);
- the leaf's measurements: sizes, areas, height and curvature ranges (curvature.py).

Lengths are in the input's units. A leaf's length is its blade's, as a botanist measures it and
as `--length` sets it (assets/placement.py): from the base, where the midrib (the first vein)
meets the outline, to the apex, the outline's farthest point along the midrib's direction; a
cordate leaf's lobes reaching back past the base are not counted. Its width is the outline's
extent across that direction, so a reniform leaf is wider than long. Without veins the direction
is the frame's u axis (the boundary's direction of largest variance, see plane.py). Both are the
flat blade's outline's (a scan's holes, trimmed from its mesh, are not cut from it: sugar beet
pot1_7's, the one of the eight scans, reaches neither end nor side). The perimeter is the
margin's 3D length on the mesh as it is: its outer boundary loops (margin_length), bent with a
bent leaf (so a posed leaf's depends on its pose: an ovate form's is 6.0% longer folded 60°, 17%
twisted 1, README's Real size); a hole's edges inside the blade are not counted, a tear or notch
reaching the margin is (the margin follows it). Both meshers put the outline first among a flat
mesh's vertices, in order, but a bend's cuts do not keep that: a scan's holes trimmed out
(core/sheet_bend.Scaled.trim) renumber the vertices, and the ring through the first ones crossed
sugar beet pot1_7's blade (215.2 mm against its margin's 195.6). A ball-pivoting mesh's margin
is its own: it bridged a cordate form's sinus, 0.86% shorter than the outline at grid 96 (the
conforming mesher's margin is the outline's, to the last bit).
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any, TypeVar

import numpy as np

from leafstudio.core.bend import flat_curves, flat_leaf
from leafstudio.core.border import (
    connected_pieces,
    count_border_loops,
    edge_counts,
    margin_length,
)
from leafstudio.core.curvature import CURVATURE_ARRAYS
from leafstudio.core.distance import mesh_distances
from leafstudio.core.plane import Frame, fit_frame, turned_along
from leafstudio.core.prepare.units import Units
from leafstudio.core.prepare.vein_order import midrib_turned, vein_order
from leafstudio.core.trianglemesh import MeshLike
from leafstudio.errors import LeafError
from leafstudio.model import Leaf


def triangles_of(mesh: MeshLike) -> np.ndarray:
    """(m, 3) vertex indices of an all-triangle mesh (a TriangleMesh or a pyvista.PolyData)."""
    faces = np.asarray(mesh.regular_faces)
    if faces.size == 0:
        return np.empty((0, 3), np.int64)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"a triangle mesh was expected, got faces of shape {faces.shape}")
    return faces


def point_to_mesh_distance(mesh: MeshLike, points: np.ndarray) -> np.ndarray:
    """(n,) exact distance from each point to the nearest point on the mesh's triangles (see
    distance.py: compiled, and without holding the GIL for long)."""
    return mesh_distances(np.asarray(mesh.points, dtype=float), triangles_of(mesh), points)


def _summary(values: np.ndarray) -> dict[str, float | None]:
    if len(values) == 0:
        return {"min": None, "max": None, "mean": None}
    return {"min": float(values.min()), "max": float(values.max()), "mean": float(values.mean())}


def surface_area(points: np.ndarray, triangles: np.ndarray) -> float:
    """Total area of the triangles over (n, d) points (d = 2 or 3)."""
    a, b, c = (points[triangles[:, i]] for i in range(3))
    if points.shape[1] == 2:
        cross = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
        return float(0.5 * np.abs(cross).sum())
    return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def facing_area(points: np.ndarray, triangles: np.ndarray) -> float:
    """The area of the triangles over (n, 3) points projected on the plane across their
    area-weighted mean normal: the mesh seen face-on as a whole, whichever way it is turned (for
    a height field over a plane, the largest projected area over all directions)."""
    a, b, c = (points[triangles[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    facing = cross.sum(axis=0)
    size = float(np.linalg.norm(facing))
    if size == 0.0:
        return 0.0
    return float(0.5 * np.abs(cross @ (facing / size)).sum())


T = TypeVar("T")
Steps = Generator[None, None, T]  # a computation that yields between its steps, then returns


def finish(steps: Steps[T]) -> T:
    """Run `steps` to its end; what it returns."""
    while True:
        try:
            next(steps)
        except StopIteration as stop:
            return stop.value


def mesh_fact_steps(mesh: MeshLike) -> Steps[dict[str, Any]]:
    """mesh_facts in steps (see table_steps)."""
    triangles = triangles_of(mesh)
    counted = edge_counts(triangles)
    yield
    components = connected_pieces(triangles, counted[0])
    yield
    loops = count_border_loops(triangles, counted)
    yield
    return {
        "triangles": len(triangles),
        "vertices": int(mesh.n_points),
        "components": components,
        "boundary_loops": loops,
        "non_manifold_edges": int((counted[1] > 2).sum()),
        "area": surface_area(np.asarray(mesh.points), triangles),
    }


def mesh_facts(mesh: MeshLike) -> dict[str, Any]:
    """Triangles, connected components, boundary loops, non-manifold edges and area."""
    return finish(mesh_fact_steps(mesh))


def table_steps(mesh: MeshLike, leaf: Leaf) -> Steps[dict[str, Any]]:
    """table_metrics in steps, yielding between them: a caller may stop there and go on later
    from where it stopped (the app's measuring gives way to a newer request: Result.measure)."""
    points = np.vstack([leaf.boundary, leaf.vein_points.reshape(-1, 3)])
    distances = point_to_mesh_distance(mesh, points)  # one search structure for both
    n = len(leaf.boundary)
    yield
    facts = yield from mesh_fact_steps(mesh)
    return {"boundary": _summary(distances[:n]), "veins": _summary(distances[n:]), "mesh": facts}


def table_metrics(mesh: MeshLike, leaf: Leaf) -> dict[str, Any]:
    """The paper's Table 1 (distances from the boundary and the vein points to the mesh) and the
    mesh's facts."""
    return finish(table_steps(mesh, leaf))


def dihedral_angles(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The angle in degrees between the normals of the two triangles at each edge two share,
    and those (e, 2) edges: how sharply a mesh creases."""
    a, b, c = (points[triangles[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1).astype(np.int64)
    face = np.repeat(np.arange(len(triangles)), 3)
    base = int(edges.max(initial=0)) + 1
    order = np.argsort(edges[:, 0] * base + edges[:, 1], kind="stable")
    edges, face = edges[order], face[order]
    pair = np.flatnonzero(np.all(edges[1:] == edges[:-1], axis=1))
    cos = np.clip((normal[face[pair]] * normal[face[pair + 1]]).sum(axis=1), -1.0, 1.0)
    return np.degrees(np.arccos(cos)), edges[pair]


def margin_creases(
    result: Any, band_cells: float = 3.0, points: np.ndarray | None = None
) -> dict[str, float]:
    """The 99th percentile of the dihedral angles (degrees) within `band_cells` grid steps of
    the margin and farther in, for a pipeline Result: a noisy margin shows as creases. `points`:
    the mesh's vertices moved (another surface on the same triangles, a form's own)."""
    import shapely

    points = np.asarray(result.triangle_mesh.points if points is None else points)
    angles, edges = dihedral_angles(points, triangles_of(result.triangle_mesh))
    xy = result.mesh_on_blade()[0]  # where the outline is (a bent leaf's: on its flat blade)
    margin = shapely.LinearRing(result.polygon)
    shapely.prepare(margin)  # its edges indexed: within the band or not, not each distance
    near = shapely.dwithin(margin, shapely.points(xy), band_cells * result.grid.spacing)
    band = near[edges].any(axis=1)  # the same as distance <= band, 2-6 times faster
    return {
        "margin_p99": float(np.percentile(angles[band], 99)),
        "interior_p99": float(np.percentile(angles[~band], 99)),
    }


#: (key, label) of the scalar measurements, in the order a table shows them
NO_MIXTURE = "unused (flat blade)"  # K where the blade fits no mixture (Result.fitted_k None)
FIELDS = (
    ("area", "surface area (3D)"),
    ("projected_area", "projected area"),
    ("perimeter", "perimeter (outer margin, 3D)"),
    ("length", "length (base to apex)"),
    ("width", "greatest width (across the midrib)"),
    ("aspect_ratio", "aspect ratio (length / width)"),
    ("height", "greatest height"),
)


def vertex_areas(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(n,) area around each vertex: a third of the area of every triangle it belongs to."""
    a, b, c = (points[triangles[:, i]] for i in range(3))
    third = np.linalg.norm(np.cross(b - a, c - a), axis=1) / 6
    return np.bincount(triangles.ravel(), np.repeat(third, 3), minlength=len(points))


def curvature_summary(mesh: MeshLike) -> dict[str, dict[str, float]]:
    """min, max and area-weighted mean of each curvature array the mesh carries."""
    weights = vertex_areas(np.asarray(mesh.points), triangles_of(mesh))
    summary = {}
    for name in CURVATURE_ARRAYS:
        if name in mesh.point_data:
            values = np.asarray(mesh.point_data[name])
            summary[name] = {
                "min": float(values.min()),
                "max": float(values.max()),
                "mean": float(np.average(values, weights=weights)),
            }
    return summary


def blade_axis(polygon: np.ndarray, midrib: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The blade's base (2,) and unit direction (2,) in the plane of its (b, 2) outline: the
    `midrib`'s ((m, 2) in that plane, or None) first-to-last direction, from where it meets the
    outline going back from its first point (its first point if it starts outside); without a
    midrib, +u from the outline's lowest u (module docstring). A midrib given shuffled is put in
    order first, as the stages put it (vein_order: a chord between two random points was not
    its direction)."""
    import shapely

    if midrib is not None:
        midrib = midrib[vein_order(midrib)]
    chord = None if midrib is None or len(midrib) < 2 else midrib[-1] - midrib[0]
    if chord is None or not np.linalg.norm(chord) > 0:
        return polygon[np.argmin(polygon[:, 0])], np.array([1.0, 0.0])
    direction = chord / np.linalg.norm(chord)
    start = midrib[0]
    far = np.ptp(polygon, axis=0).sum() * 2  # a ray long enough to leave the leaf
    ray = shapely.LineString([start, start - far * direction])
    points = shapely.get_coordinates(shapely.intersection(shapely.LinearRing(polygon), ray))
    if not len(points):  # the midrib starts outside the outline: its first point is the base
        return start, direction
    return points[np.argmin(np.linalg.norm(points - start, axis=1))], direction


def leaf_axis(leaf: Leaf, frame: Frame, polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """blade_axis of a leaf whose flat blade's outline in `frame`'s plane is the (b, 2)
    `polygon`: its midrib (blade_midrib: on the flat blade of a bent leaf) taken into that plane."""
    midrib = blade_midrib(leaf)
    return blade_axis(polygon, None if midrib is None else frame.to_plane(midrib)[0])


def blade_midrib(leaf: Leaf) -> np.ndarray | None:
    """The leaf's midrib (its first vein) on its flat blade, (m, 3), base first: turned round
    when its side veins lean toward its first point (vein_order.leans_back: they leave the
    midrib toward the apex; a midrib written apex first put an export's apex at the origin),
    which leaf_warnings says; None without one."""
    if not leaf.veins or len(leaf.veins[0]) < 2:
        return None
    veins = leaf.veins if leaf.bend is None else flat_curves(leaf.bend, list(leaf.veins), [])
    return veins[0][::-1] if midrib_turned(veins) else veins[0]


def leaf_blade_length(leaf: Leaf) -> float:
    """A leaf's blade length from its points alone, before any reconstruction (what `extract`
    reports): blade_axis on its flat blade's outline in the outline's PCA plane (a result's
    traced outline may differ from the points by their noise)."""
    units = Units.of(flat_leaf(leaf))  # at unit size, as the pipeline (a scan at 1e200 overflows)
    flat = units.leaf(flat_leaf(leaf))
    frame = fit_frame(flat.boundary, flat.vein_points)
    polygon = frame.to_plane(flat.boundary)[0]
    base, direction = leaf_axis(flat, frame, polygon)
    return units.scale * blade_length_width(polygon, base, direction)[0]


def view_frame(result: Any) -> Frame:
    """The frame a result is shown on: its plane's, turned a quarter or half turn so that u runs
    nearest its midrib, base to apex (blade_axis): the app's sketch and 3D view, the figures and
    the slides show every leaf base left, apex right (the plane's u runs to the outline's
    farther extreme: an obovate leaf's base). Without a midrib, the plane's frame."""
    direction = leaf_axis(result.leaf, result.frame, result.polygon)[1]  # +u without a midrib
    return turned_along(result.frame, direction)


def blade_length_width(
    polygon: np.ndarray, base: np.ndarray, direction: np.ndarray
) -> tuple[float, float]:
    """The blade's length from `base` to its apex along `direction` and its width across it."""
    along = (polygon - base) @ direction
    across = polygon @ np.array([-direction[1], direction[0]])
    return float(along.max()), float(np.ptp(across))


def shape_measurements(
    mesh: MeshLike,
    frame: Frame,
    polygon: np.ndarray,
    area: float | None = None,
    midrib: np.ndarray | None = None,
    face_on: bool = False,
    blade_xy: np.ndarray | None = None,
) -> dict[str, float]:
    """The FIELDS measurements of a leaf mesh.

    Parameters
    ----------
    mesh : TriangleMesh or pyvista.PolyData
        The leaf's triangle mesh in world coordinates, with the point array "height"; its
        perimeter is its outer boundary loops' length (margin_length).
    frame : Frame
        The leaf's plane frame (u: the main axis).
    polygon : (b, 2) float array
        The outline in plane coordinates.
    area : float, optional
        The mesh's surface area, when it is known already (mesh_facts has it).
    midrib : (m, 3) float array, optional
        The midrib (the first vein) of the flat blade, in world coordinates: the length is along
        it, base to apex (blade_axis); without it, along u.
    face_on : bool, default: False
        The projected area is the mesh seen along its own mean normal (`facing_area`), not on
        `frame`'s plane: for a bent blade whose flat blade's plane is not the leaf's own (a
        scan's sheet lays it on the world's x-y plane, core/sheet_bend.Scaled.own_plane: its
        projected area was its shadow on the scanner's x-y plane, 137 to 376 for sugar beet
        pot1_1 as it was turned).
    blade_xy : (n, 2) float array, optional
        A bent mesh's points on its flat blade, in `frame`'s plane (Result.blade_xy), which
        margin_length tells the outer loops by; without it, the mesh's points in that plane.

    Returns
    -------
    dict
        The FIELDS keys as floats (aspect_ratio None for an outline of no width).
    """
    points = np.asarray(mesh.points)
    triangles = triangles_of(mesh)
    plane_xy, _ = frame.to_plane(points)
    kept = blade_xy is not None and len(blade_xy) == len(points)  # else another mesh's
    flat_xy = blade_xy if kept else plane_xy
    base, direction = blade_axis(polygon, None if midrib is None else frame.to_plane(midrib)[0])
    length, width = blade_length_width(polygon, base, direction)
    return {
        "area": surface_area(points, triangles) if area is None else area,
        "projected_area": facing_area(points, triangles)
        if face_on
        else surface_area(plane_xy, triangles),
        "perimeter": margin_length(points, triangles, flat_xy),
        "length": length,
        "width": width,
        "aspect_ratio": length / width if width > 0 else None,
        "height": float(np.ptp(np.asarray(mesh.point_data["height"]))),
    }


def leaf_measurements(result: Any) -> dict[str, Any]:
    """Every measurement of a Result: its shape (FIELDS), the K used, its curvature ranges and
    the Table-1 distances, all from `result.metrics` (which holds them; see Result.metrics).

    Returns
    -------
    dict
        The FIELDS keys, "k" (None: a flat blade fits no mixture), "curvature"
        (curvature_summary) and "boundary"/"veins" (the Table-1 min, max and mean distances).
    """
    metrics = result.metrics
    return {
        **metrics["leaf"],
        "curvature": metrics["curvature"],
        "boundary": metrics["boundary"],
        "veins": metrics["veins"],
    }


def format_table(values: dict[str, Any]) -> str:
    """The measurements as an aligned two-column text table."""

    def number(x: float | None) -> str:
        return "-" if x is None else f"{x:.6g}"

    rows = [(label, number(values[key])) for key, label in FIELDS]
    k = values["k"]
    rows.append(("K (Gaussians)", NO_MIXTURE if k is None else str(k)))
    for name, stats in values["curvature"].items():
        rows.append(
            (
                f"{name.replace('_', ' ')} min / mean / max",
                " / ".join(number(stats[s]) for s in ("min", "mean", "max")),
            )
        )
    for part in ("boundary", "veins"):
        stats = values[part]
        rows.append(
            (
                f"distance {part} -> mesh min / mean / max",
                " / ".join(number(stats[s]) for s in ("min", "mean", "max")),
            )
        )
    width = max(len(label) for label, _ in rows)
    return "\n".join(f"{label:<{width}}  {value}" for label, value in rows)


MEASURABLE = 1e150  # an area (size²) of a leaf this long stays finite in float64


def check_finite(figures: Any) -> None:
    """LeafError when a figure (a float anywhere in nested dicts and lists) is not finite: a
    leaf near float64's limits has areas (size²) that overflow (fuzzing, issue 24: at 1e154,
    `measure` printed infinite areas and --metrics held Infinity; `Result.metrics` of a leaf
    spanning 1e300 held an infinite area)."""

    def numbers(value: object) -> list[float]:
        if isinstance(value, dict):
            return [n for v in value.values() for n in numbers(v)]
        if isinstance(value, list | tuple):
            return [n for v in value for n in numbers(v)]
        return [float(value)] if isinstance(value, float) else []

    if not all(np.isfinite(numbers(figures))):
        raise LeafError(
            "the leaf is too large (or too small) to measure: its areas or curvatures overflow; "
            f"rescale it (coordinates up to about {MEASURABLE:g} are measured)"
        )
